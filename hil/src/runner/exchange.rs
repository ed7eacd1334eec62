//! What one period sends a vehicle's firmware — navigation, sonar or contacts, with the
//! scenario's sensor faults — and collects from it: its command for the period, its replies and
//! telemetry, recorded with the true clearance.

use std::time::Duration;

use vpf::link::{ContactList, ContactsRepr, Message, NavRepr, TickRepr};

use crate::firmware::{Reply, Target};
use crate::scenario::{RunMode, Scenario, Sensing, Window};
use crate::sim::contacts::{self, OtherVehicle};
use crate::types::{SetPoints, VehicleState, P2};

use super::simulate::SimVehicle;
use super::{RunError, TICK_ATTEMPTS, TICK_RETRY, TICK_RETRY_HOST};

/// Sends this period's navigation and sonar, with the scenario's sensor faults. A Ping360 of
/// its own is served first, while the main link is quiet (`crate::ping360::sim` says why).
pub(super) fn send_sensors(
    s: &mut SimVehicle,
    sc: &Scenario,
    t: f64,
    truth: &VehicleState,
    others: &[OtherVehicle],
) -> Result<(), RunError> {
    let t_ms = (t * 1000.0).round() as u64;
    let in_window = |w: &Option<Window>| w.as_ref().is_some_and(|w| w.contains(t));
    if let Some((p, tap, expected)) = s.ping360.as_mut() {
        let lockstep = sc.mode == RunMode::Lockstep;
        let hulls: Vec<(P2, f64)> = others.iter().map(|o| (o.position, o.hull_radius)).collect();
        tap.t = t;
        p.sync(*expected, (t - sc.dt_s).max(0.0), lockstep)?;
        p.answer(
            t,
            truth,
            &sc.obstacles,
            &hulls,
            &mut s.sonar,
            tap,
            lockstep,
            in_window(&sc.faults.sonar_dropout),
        )?;
    }
    let fresh = s.nav.sample(t, truth);
    let nav = if in_window(&sc.faults.nav_freeze) {
        *s.frozen.get_or_insert(fresh)
    } else {
        s.frozen = None;
        fresh
    };
    s.delayed
        .push_back((t + sc.faults.nav_delay_ms / 1000.0, nav));
    let mut latest = None;
    while s.delayed.front().is_some_and(|(due, _)| *due <= t + 1e-9) {
        latest = s.delayed.pop_front().map(|(_, n)| n);
    }
    if let (Some(nav), false) = (latest, in_window(&sc.faults.nav_loss)) {
        let m = Message::Nav(NavRepr {
            time_ms: t_ms,
            nav,
            body: None,
        });
        s.fw.send(&m, &mut s.tap)?;
    }
    if in_window(&sc.faults.sonar_dropout) {
        return Ok(());
    }
    match s.sensing {
        Sensing::Sonar if s.ping360.is_some() => {
            if sc.sonar.vehicle_contacts {
                send_contacts(s, t, t_ms, truth, &[], others, sc.sonar.range_m)?;
            }
        }
        Sensing::Sonar => {
            let hulls: Vec<(P2, f64)> =
                others.iter().map(|o| (o.position, o.hull_radius)).collect();
            for ping in s.sonar.poll(t, truth, &sc.obstacles, &hulls) {
                s.fw.send(&Message::Scanline(ping.as_scanline()), &mut s.tap)?;
            }
            if sc.sonar.vehicle_contacts {
                send_contacts(s, t, t_ms, truth, &[], others, sc.sonar.range_m)?;
            }
        }
        Sensing::Contacts => {
            send_contacts(s, t, t_ms, truth, &sc.obstacles, others, sc.sonar.range_m)?
        }
    }
    Ok(())
}

/// Sends the obstacles and vehicles within `range` m as contacts.
pub(super) fn send_contacts(
    s: &mut SimVehicle,
    t: f64,
    t_ms: u64,
    truth: &VehicleState,
    obstacles: &[crate::types::SimObstacle],
    others: &[OtherVehicle],
    range: f64,
) -> Result<(), RunError> {
    let found = contacts::contacts(t, truth, obstacles, others, range);
    for chunk in found.chunks(vpf::link::MAX_CONTACTS) {
        let m = Message::Contacts(ContactsRepr {
            time_ms: t_ms,
            contacts: ContactList::new(chunk),
        });
        s.fw.send(&m, &mut s.tap)?;
    }
    Ok(())
}

/// Collects the firmware's answer for this period and records it.
pub(super) fn collect(s: &mut SimVehicle, mode: RunMode, t_ms: u64) -> Result<(), RunError> {
    let got = match mode {
        RunMode::Lockstep => {
            let mut attempt = 1;
            loop {
                let answered = |inbox: &[Reply]| {
                    inbox
                        .iter()
                        .any(|r| matches!(r, Reply::Command(c) if c.time_ms == t_ms))
                };
                let wait = if s.fw.target == Target::Host {
                    TICK_RETRY_HOST
                } else {
                    TICK_RETRY
                };
                match s.fw.receive_until(wait, &mut s.tap, answered) {
                    Ok(got) => break got,
                    Err(e)
                        if e.kind() == std::io::ErrorKind::TimedOut && attempt < TICK_ATTEMPTS =>
                    {
                        attempt += 1;
                        s.tick_retries += 1;
                        s.resent = Some(t_ms);
                        s.fw.send(&Message::Tick(TickRepr { time_ms: t_ms }), &mut s.tap)?;
                    }
                    Err(e) => return Err(e.into()),
                }
            }
        }
        RunMode::Realtime => s.fw.receive_until(Duration::ZERO, &mut s.tap, |_| true)?,
    };
    if let Some(resent) = s.resent {
        // A period whose Tick went out twice and came back answered twice (now, or with the
        // next period's answers) had only been slow; once, and a Tick was lost.
        let answers = got
            .iter()
            .filter(|r| matches!(r, Reply::Command(c) if c.time_ms == resent))
            .count();
        if answers >= 2 || (answers == 1 && resent != t_ms) {
            s.ticks_slow += 1;
        }
        if answers >= 2 || resent != t_ms {
            s.resent = None;
        }
    }
    for r in &got {
        match r {
            // A rejected set-up request ends the run; a busy one goes again.
            Reply::Reply(rep) => s.upload.on_reply(rep)?,
            Reply::Belief(c) => {
                let position = s.model.state().position;
                s.record.belief.apply(c, t_ms as f64 * 1e-3, position);
            }
            Reply::Telemetry(tel) => {
                if let Some((_, _, expected)) = s.ping360.as_mut() {
                    *expected = tel.ping360.commands;
                }
                s.record.telemetry = Some(*tel);
                s.record.cost_unit = Some(tel.cost_unit);
                if tel.step_cost > 0 {
                    s.record.step_costs.push(tel.step_cost);
                }
            }
            _ => {}
        }
    }
    let command = got.iter().rev().find_map(|r| match r {
        Reply::Command(c) => Some(c.command),
        _ => None,
    });
    if let Some(c) = command {
        let sp = &c.setpoints;
        s.setpoints = SetPoints {
            psi: f64::from(c.psi_set),
            speed: f64::from(c.v_set),
            velocity: P2::new(f64::from(c.velocity.x), f64::from(c.velocity.y)),
            pid: crate::types::PidFeeds {
                a_c: f64::from(sp.a_c),
                v_c: f64::from(sp.v_c),
                i_surge: f64::from(sp.i_surge),
                alpha_c: f64::from(sp.alpha_c),
                omega_c: f64::from(sp.omega_c),
                phi_c: f64::from(sp.phi_c),
            },
        };
        let target = P2::new(f64::from(c.target.x), f64::from(c.target.y));
        if target.sub(s.record.goal).norm() > 0.5
            && !s.record.ghosts.iter().any(|g| g.sub(target).norm() < 0.5)
            && c.ghost_depth > 0
        {
            s.record.ghosts.push(target);
        }
        // Time, state and clearance are filled in by the caller.
        s.record.samples.push(crate::types::Sample {
            t: 0.0,
            state: VehicleState::default(),
            psi_cmd: f64::from(c.psi_set),
            speed_cmd: f64::from(c.v_set),
            mode: format!("{:?}", c.mode),
            ghost_depth: c.ghost_depth,
            target,
            nearest_m: f64::INFINITY,
        });
    } else if let Some(prev) = s.record.samples.last().cloned() {
        // Real time, nothing new: the vehicle keeps following the last command.
        s.record.samples.push(prev);
    }
    Ok(())
}

/// True clearance: distance from the hull to the nearest obstacle surface or other hull.
pub(super) fn nearest(
    sc: &Scenario,
    t: f64,
    state: &VehicleState,
    hull: f64,
    others: &[(P2, f64)],
    me: usize,
) -> f64 {
    let p = state.position;
    let obstacles = sc.obstacles.iter().map(|o| o.signed_distance(t, p) - hull);
    let vehicles = others
        .iter()
        .enumerate()
        .filter(|(j, _)| *j != me)
        .map(|(_, (q, r))| q.sub(p).norm() - hull - r);
    obstacles.chain(vehicles).fold(f64::INFINITY, f64::min)
}
