//! The guidance runtime end to end on the host, over the real wire protocol: frames in (with
//! garbage), commands, telemetry and replies out, decoded as a host would decode them.

use vpf::field::Shape;
use vpf::guidance::{FailsafeConfig, OneThreadRuntime, RuntimeConfig};
use vpf::link::{
    ChartObstacleRepr, Contact, ContactKind, ContactList, ContactsRepr, CostUnit, Decoder,
    Direction, Message, MessageType, NavRepr, Outcome, ReplyStatus, TickRepr, MAX_FRAME,
};
use vpf::planner::HoldReason;
use vpf::sonar::Scanline;
use vpf::{Mission, Mode, NavState, Params, Strategy, Vec2};

/// A host talking to a [`OneThreadRuntime`]: frames out, everything the firmware sent decoded.
struct Host {
    fw: OneThreadRuntime,
    seq: u16,
    decoder: Decoder,
    commands: Vec<vpf::link::CommandRepr>,
    telemetry: Vec<vpf::link::TelemetryRepr>,
    replies: Vec<vpf::link::ReplyRepr>,
}

impl Host {
    fn new(params: Params) -> Self {
        Host {
            fw: OneThreadRuntime::new(params, RuntimeConfig::default(), CostUnit::Unknown).unwrap(),
            seq: 0,
            decoder: Decoder::accepting(Direction::ToHost),
            commands: vec![],
            telemetry: vec![],
            replies: vec![],
        }
    }

    fn frame(&mut self, m: Message<'_>) -> Vec<u8> {
        let mut buf = [0u8; MAX_FRAME];
        self.seq = self.seq.wrapping_add(1);
        let n = m.emit_frame(self.seq, &mut buf).unwrap();
        buf[..n].to_vec()
    }

    fn send_bytes(&mut self, bytes: &[u8]) {
        let mut out = Vec::new();
        // A clock that ticks once per reading: a planner step costs 1.
        let mut clock = 0u32;
        let mut cost = || {
            clock += 1;
            clock
        };
        self.fw.on_bytes(bytes, &mut cost, &mut |f: &[u8]| {
            out.extend_from_slice(f);
            true
        });
        self.receive(&out);
    }

    fn send(&mut self, m: Message<'_>) {
        let f = self.frame(m);
        self.send_bytes(&f);
    }

    fn receive(&mut self, bytes: &[u8]) {
        for &b in bytes {
            if let Outcome::Frame(_, m) = self.decoder.push(b) {
                match m {
                    Message::Command(c) => self.commands.push(c),
                    Message::Telemetry(t) => self.telemetry.push(t),
                    Message::Reply(r) => self.replies.push(r),
                    _ => {}
                }
            }
        }
    }

    fn nav(&mut self, t: u64, p: Vec2, v: Vec2) {
        let nav = NavState {
            position: p,
            heading: if v.norm() > 0.01 { v.angle() } else { 0.0 },
            velocity: v,
        };
        self.send(Message::Nav(NavRepr {
            time_ms: t,
            nav,
            body: None,
        }));
    }

    fn tick(&mut self, t: u64) -> vpf::Command {
        let before = self.commands.len();
        self.send(Message::Tick(TickRepr { time_ms: t }));
        assert_eq!(self.commands.len(), before + 1, "one command per tick");
        self.commands.last().unwrap().command
    }
}

fn mission(goal: Vec2) -> Message<'static> {
    Message::Mission(Mission {
        goal,
        formation: None,
    })
}

/// Lockstep: a kinematic vehicle driven only by the commands it receives over the link reaches
/// its goal past a charted obstacle, with garbage on the line between frames.
#[test]
fn lockstep_vehicle_reaches_goal_through_garbage() {
    // σ sized to the 30 m mission, so the final approach is not the Gaussian's slow tail.
    let mut host = Host::new(Params {
        sigma_m: 20.0,
        ..Params::default()
    });
    host.send(mission(Vec2::new(30.0, 0.0)));
    let rock = Shape::circle(Vec2::new(15.0, 0.5), 2.0).unwrap();
    host.send(Message::ChartObstacle(ChartObstacleRepr {
        id: 1,
        shape: rock,
        a_plus: 2.5,
    }));
    // Requests are applied, and answered, by the next period.
    assert!(host.replies.is_empty());
    host.tick(0);
    assert_eq!(host.replies.len(), 2);
    assert!(host
        .replies
        .iter()
        .all(|r| r.status == ReplyStatus::Accepted));

    let (mut p, mut v) = (Vec2::ZERO, Vec2::ZERO);
    let mut min_clearance = f32::INFINITY;
    let mut garbage_sent = 0;
    for k in 1..1500u64 {
        let t = k * 100;
        host.nav(t, p, v);
        if k % 7 == 3 {
            // Line noise, including a stray delimiter and a frame cut short.
            host.send_bytes(&[0x55, 0x13, 0x00, 0xFF, 0x02, 0x41, 0x00]);
            garbage_sent += 1;
        }
        let cmd = host.tick(t);
        v = cmd.velocity;
        p += v * 0.1;
        min_clearance = min_clearance.min((p - Vec2::new(15.0, 0.5)).norm() - 2.0);
    }
    let last = host.commands.last().unwrap().command;
    let tel = host.telemetry.last().unwrap();
    println!(
        "final {p:?}, mode {:?}, min clearance {min_clearance:.2} m, counters {:?}",
        last.mode, tel.counters
    );
    assert!(
        (p - Vec2::new(30.0, 0.0)).norm() < 1.0,
        "did not reach the goal: {p:?}"
    );
    assert_eq!(last.mode, Mode::Arrived);
    assert!(min_clearance > 0.0);
    assert_eq!(tel.obstacles, 1);
    assert!(tel.counters.rx_framing_errors + tel.counters.rx_crc_errors >= garbage_sent);
    assert_eq!(tel.counters.tx_frames_dropped, 0);
    assert_eq!(host.commands.len(), 1500);
}

/// Navigation stops: the late fix is carried forward and the vehicle slows, the fail-safe holds
/// it once the fix is older than the navigation timeout, and planning resumes when navigation
/// returns.
#[test]
fn late_navigation_is_dead_reckoned_and_slowed_then_stale_navigation_holds() {
    let mut host = Host::new(Params::default());
    host.send(mission(Vec2::new(30.0, 0.0)));
    let mut p = Vec2::ZERO;
    let mut v = Vec2::ZERO;
    for k in 0..50u64 {
        host.nav(k * 100, p, v);
        let c = host.tick(k * 100);
        v = c.velocity;
        p += v * 0.1;
    }
    assert!(v.norm() > 0.1);
    // Last navigation at t = 4900 ms; ticks go on without it.
    let timeout = FailsafeConfig::default().nav_timeout_ms;
    let after: Vec<_> = (50..=49 + (timeout / 100) + 2)
        .map(|k| host.tick(k * 100))
        .collect();
    assert_eq!(after[0].mode, Mode::Transit, "one period of grace");
    // Late: still in transit, the speed bounded by a share of v_max that falls to zero.
    let v_max = Params::default().v_max;
    for (i, c) in after.iter().enumerate().skip(1) {
        let age = 100 * (i as u64 + 1);
        if age > timeout {
            assert_eq!(c.mode, Mode::Hold(HoldReason::StaleNav), "age {age} ms");
            assert_eq!(c.v_set, 0.0);
        } else {
            assert_eq!(c.mode, Mode::Transit, "age {age} ms: dead-reckoned");
            let share = 1.0 - (age - 100) as f32 / (timeout - 100) as f32;
            assert!(c.v_set <= share * v_max + 1e-6, "age {age}: {}", c.v_set);
        }
    }
    assert!(
        after[1].v_set > 0.0,
        "a lost frame does not stop the vehicle"
    );
    // Held within two periods of the timeout.
    assert!(after
        .iter()
        .any(|c| c.mode == Mode::Hold(HoldReason::StaleNav)));
    host.nav(7000, p, Vec2::ZERO);
    assert_eq!(host.tick(7000).mode, Mode::Transit);
}

/// A held period reports no step cost, not the last step's: the self-test's and the harness's
/// cost figures count only periods that planned.
#[test]
fn a_held_period_reports_no_step_cost() {
    let mut host = Host::new(Params::default());
    host.send(mission(Vec2::new(30.0, 0.0)));
    host.nav(0, Vec2::ZERO, Vec2::ZERO);
    assert_eq!(host.tick(0).mode, Mode::Transit);
    assert_eq!(
        host.telemetry.last().unwrap().step_cost,
        1,
        "one reading of the clock"
    );
    let timeout = FailsafeConfig::default().nav_timeout_ms;
    let held = host.tick(timeout + 200);
    assert_eq!(held.mode, Mode::Hold(HoldReason::StaleNav));
    assert_eq!(host.telemetry.last().unwrap().step_cost, 0);
}

/// A parameter set with a bad value gets a typed rejection naming the parameter, and the old
/// parameters stay in force; a mission before navigation is held, not planned.
#[test]
fn bad_parameters_get_a_typed_rejection() {
    let mut host = Host::new(Params::default());
    let bad = Params {
        v_max: 50.0,
        ..Params::default()
    };
    host.send(Message::Params(bad));
    host.send(mission(Vec2::new(5.0, 5.0)));
    let c = host.tick(0);
    assert_eq!(c.mode, Mode::Hold(HoldReason::StaleNav));
    let r = host.replies[0];
    assert_eq!(r.to_type, MessageType::Params);
    let v_max = vpf::link::param_index("v_max").unwrap();
    assert_eq!(
        r.status,
        ReplyStatus::Rejected {
            field: v_max,
            problem: vpf::link::Problem::OutOfRange
        }
    );
    assert_eq!(host.replies[1].status, ReplyStatus::Accepted);
    assert_eq!(host.fw.periodic().planner().params().v_max, 1.0);
    assert_eq!(host.telemetry.last().unwrap().counters.bad_params, 1);
}

/// Sonar scanlines from a sweep past a rock become an obstacle in the firmware's table.
#[test]
fn scanlines_become_obstacles() {
    let mut host = Host::new(Params::default());
    host.send(mission(Vec2::new(30.0, 0.0)));
    let rock = Vec2::new(12.0, 3.0);
    let radius = 1.5f32;
    host.nav(0, Vec2::ZERO, Vec2::ZERO);
    // One sweep from −90° to +90°, 1.8° a step, 30 m range, 300 bins; vehicle at rest at the origin.
    let bins_n = 300usize;
    let range = 30.0f32;
    let step = 1.8f32.to_radians();
    for i in 0..=100 {
        let bearing = -std::f32::consts::FRAC_PI_2 + i as f32 * step;
        let dir = Vec2::from_angle(bearing);
        let mut bins = vec![0u8; bins_n];
        // Ray–circle intersection: first hit distance along `dir`.
        let b = dir.dot(rock);
        let c = rock.norm2() - radius * radius;
        let disc = b * b - c;
        if disc > 0.0 {
            let hit = b - disc.sqrt();
            let bin = (hit / range * bins_n as f32) as usize;
            bins.iter_mut().skip(bin).take(4).for_each(|b| *b = 200);
        }
        let scan = Scanline {
            time_ms: i as u64 * 50,
            bearing_rad: bearing,
            step_rad: step,
            range_m: range,
            bins: &bins,
        };
        host.send(Message::Scanline(scan));
    }
    // Finish the sweep (reverse direction closes the open clusters), then tick.
    let bins = vec![0u8; bins_n];
    for i in 0..3 {
        let scan = Scanline {
            time_ms: 5100 + i * 50,
            bearing_rad: std::f32::consts::FRAC_PI_2 - (i as f32 + 1.0) * step,
            step_rad: step,
            range_m: range,
            bins: &bins,
        };
        host.send(Message::Scanline(scan));
    }
    host.nav(5300, Vec2::ZERO, Vec2::ZERO);
    host.tick(5300);
    let tel = host.telemetry.last().unwrap();
    let world = host.fw.periodic().world();
    println!(
        "features {}, obstacles {:?}",
        tel.counters.features_extracted,
        world.obstacles()
    );
    assert!(tel.counters.features_extracted >= 1);
    assert_eq!(tel.obstacles, 1);
    let o = world.obstacles()[0];
    assert!((o.shape.center() - rock).norm() < 0.5, "{:?}", o.shape);
}

/// More contacts in one period than the sighting queue holds: the excess is dropped and
/// counted, the rest land in the table.
#[test]
fn a_flood_of_contacts_is_counted_not_fatal() {
    let mut host = Host::new(Params::default());
    host.send(mission(Vec2::new(30.0, 0.0)));
    host.nav(0, Vec2::ZERO, Vec2::ZERO);
    for batch in 0..5u16 {
        let contacts: Vec<Contact> = (0..8u16)
            .map(|i| Contact {
                id: batch * 8 + i,
                kind: ContactKind::Obstacle,
                shape: Shape::circle(
                    Vec2::new(10.0 + i as f32 * 3.0, 5.0 + batch as f32 * 4.0),
                    1.0,
                )
                .unwrap(),
                velocity: Vec2::ZERO,
                confidence: 0.9,
            })
            .collect();
        host.send(Message::Contacts(ContactsRepr {
            time_ms: 0,
            contacts: ContactList::new(&contacts),
        }));
    }
    host.tick(0);
    let tel = host.telemetry.last().unwrap();
    assert_eq!(tel.counters.features_dropped, 40 - 16);
    assert_eq!(tel.obstacles, 16);
}

/// A repeated `Tick` (the harness's start-up Tick is one) takes the sightings that came before
/// it into the table: a period's worth of contacts each period never overflows their queue.
#[test]
fn a_repeated_tick_takes_the_sightings_in() {
    let mut host = Host::new(Params::default());
    host.send(mission(Vec2::new(30.0, 0.0)));
    host.nav(0, Vec2::ZERO, Vec2::ZERO);
    host.tick(0);
    let contacts: Vec<Contact> = (0..10u16)
        .map(|i| Contact {
            id: i,
            kind: ContactKind::Obstacle,
            shape: Shape::circle(Vec2::new(10.0 + i as f32 * 3.0, 5.0), 1.0).unwrap(),
            velocity: Vec2::ZERO,
            confidence: 0.9,
        })
        .collect();
    for t in [0, 100] {
        for half in contacts.chunks(5) {
            host.send(Message::Contacts(ContactsRepr {
                time_ms: t,
                contacts: ContactList::new(half),
            }));
        }
        host.tick(t);
    }
    let tel = host.telemetry.last().unwrap();
    assert_eq!(tel.counters.features_dropped, 0);
    assert_eq!(tel.obstacles, 10);
}

/// A `Tick` repeated for the same time (the host's answer was slow or lost) gets the same
/// command again, without a second planner step: lockstep results do not depend on timing.
#[test]
fn a_repeated_tick_repeats_the_command_without_planning_again() {
    let mut host = Host::new(Params::default());
    host.send(mission(Vec2::new(30.0, 0.0)));
    host.nav(0, Vec2::ZERO, Vec2::ZERO);
    let first = host.tick(0);
    host.nav(100, Vec2::ZERO, Vec2::ZERO);
    let a = host.tick(100);
    let again = host.tick(100);
    assert_eq!(a, again);
    let b = host.tick(200);
    // A second step at t = 100 would have integrated the force once more.
    let mut reference = Host::new(Params::default());
    reference.send(mission(Vec2::new(30.0, 0.0)));
    reference.nav(0, Vec2::ZERO, Vec2::ZERO);
    assert_eq!(reference.tick(0), first);
    reference.nav(100, Vec2::ZERO, Vec2::ZERO);
    reference.tick(100);
    assert_eq!(reference.tick(200), b);
}

/// Time sanity (`docs/protocol.md`): navigation stamped more than a second after the firmware's
/// time is refused and counted, so the stale-navigation hold still comes; a `Tick` that goes
/// back in time is refused, counted and not answered.
#[test]
fn navigation_from_the_future_and_ticks_that_go_back_are_refused() {
    let mut host = Host::new(Params::default());
    host.send(mission(Vec2::new(30.0, 0.0)));
    host.nav(0, Vec2::ZERO, Vec2::ZERO);
    host.tick(0);
    // A fix stamped an hour ahead, then silence: without the rule it would look fresh forever.
    host.nav(3_600_000, Vec2::new(0.1, 0.0), Vec2::ZERO);
    let mut cmd = host.tick(100);
    let stale = FailsafeConfig::default().nav_timeout_ms + 100;
    for t in (200..=stale).step_by(100) {
        cmd = host.tick(t);
    }
    assert_eq!(cmd.mode, Mode::Hold(HoldReason::StaleNav));
    let t = host.telemetry.last().unwrap();
    assert_eq!(t.counters.bad_nav, 1, "refused once, counted once");
    let bad_payload = t.counters.rx_bad_payload;

    // A tick before the last one: no command, counted with the refused payloads.
    let before = host.commands.len();
    host.send(Message::Tick(TickRepr {
        time_ms: stale - 500,
    }));
    assert_eq!(
        host.commands.len(),
        before,
        "a tick back in time is not answered"
    );
    host.nav(stale + 100, Vec2::ZERO, Vec2::ZERO);
    host.tick(stale + 100);
    let t = host.telemetry.last().unwrap();
    assert_eq!(t.counters.rx_bad_payload, bad_payload + 1);
    assert_eq!(t.counters.bad_nav, 1);
}

/// Issue 12 §1, goals at any range: through the whole runtime (route layer on, default
/// parameters but the arrival radius), a kinematic vehicle in open water reaches goals 1 m to
/// 10 km away, in five directions, with each strategy: in the straight line's time at v_max and
/// a few seconds to speed up and brake, cruising at v_max (the cruise goal-point, `goal_point`
/// in `src/planner/vpf.rs`), and it stops inside the arrival radius (the arrival brake,
/// `arrival_speed` in `src/planner/mod.rs`).
#[test]
fn goals_from_one_metre_to_ten_kilometres_are_reached_at_cruise_speed() {
    for strategy in [Strategy::Vpf, Strategy::Multipoint, Strategy::Navfn] {
        let prm = Params {
            strategy,
            // Under the shortest mission's 1 m, so it is flown, not arrived at the start.
            arrival_radius_m: 0.5,
            ..Params::default()
        };
        for (d, bearing_deg) in [
            (1.0f32, 0.0f32),
            (10.0, 90.0),
            (150.0, 200.0),
            (1_000.0, -45.0),
            (10_000.0, 135.0),
        ] {
            let mut host = Host::new(prm);
            let start = Vec2::new(-37.0, 12.5);
            let b = bearing_deg.to_radians();
            let goal = start + Vec2::new(b.cos(), b.sin()) * d;
            host.send(mission(goal));
            // The truth integrated in f64: 10⁵ steps of 0.1 m in f32 drift by metres at 10 km.
            let (mut x, mut y) = (f64::from(start.x), f64::from(start.y));
            let (mut p, mut v) = (start, Vec2::ZERO);
            let straight_s = d / prm.v_max;
            let mut arrived_s = None;
            // Speed over the middle 80 % of the way.
            let (mut middle_m, mut middle_s) = (0.0f32, 0.0f32);
            for k in 0..((straight_s + 60.0) * 10.0) as u64 {
                let t = k * 100;
                host.nav(t, p, v);
                let cmd = host.tick(t);
                assert!(cmd.velocity.is_finite(), "{strategy:?}, {d} m: {cmd:?}");
                let gone = (p - start).norm();
                if arrived_s.is_none() && gone > 0.1 * d && gone < 0.9 * d {
                    middle_m += cmd.velocity.norm() * 0.1;
                    middle_s += 0.1;
                }
                v = cmd.velocity;
                x += 0.1 * f64::from(v.x);
                y += 0.1 * f64::from(v.y);
                p = Vec2::new(x as f32, y as f32);
                if cmd.mode == Mode::Arrived && arrived_s.is_none() {
                    arrived_s = Some(t as f32 / 1000.0);
                }
            }
            let arrived_s =
                arrived_s.unwrap_or_else(|| panic!("{strategy:?}, {d} m: not arrived, at {p:?}"));
            let cruise = middle_m / middle_s;
            let run = format!("{strategy:?}, {d} m");
            let off = (p - goal).norm();
            println!(
                "{run}: arrived after {arrived_s:.1} s ({straight_s:.0} s at v_max), \
                 {cruise:.3} m/s over the middle, stopped {off:.2} m from the goal"
            );
            assert!(arrived_s <= straight_s + 10.0, "{run}: {arrived_s} s");
            assert!(off <= prm.arrival_radius_m, "{run}: {p:?}");
            assert!(v.norm() < 0.01, "{run}: still moving {v:?}");
            if d >= 150.0 {
                assert!(cruise > 0.98 * prm.v_max, "{run}: {cruise} m/s");
            }
        }
    }
}
