//! The slow, preemptible half of the runtime: bytes in, navigation, sightings and requests out.
//!
//! Received bytes go through the stream decoder (`crate::link`); each accepted frame is
//! dispatched: navigation to the newest-navigation slot, scanlines through sonar feature
//! extraction, contacts as sightings, missions, parameters and charts as requests, ticks to the
//! lockstep clock. Requests refused at the wire, and requests that find the request queue full
//! ("busy"), get their reply through the ring of owed replies instead. Everything leaves
//! through a [`BackgroundOutputs`], which the board implements with lock-free queues.

use crate::link::{Decoder, Direction, Message, MessageType, Outcome, ReplyRepr, RxCounters};
use crate::route::{Route, Router};
use crate::sonar::{ConfigError, EvidenceMap, Extractor, ExtractorConfig, Pose, Scanline};

use super::{Control, NavSample, Sighting};
use crate::planner::NavState;

/// Where the background's results go: the writing ends of the queues and slots whose reading
/// ends are the periodic task's [`PeriodicInputs`](super::PeriodicInputs). Each `false` means
/// "full": the item is dropped and counted.
pub trait BackgroundOutputs {
    /// Publishes the newest navigation (overwrites the previous one).
    fn nav(&mut self, sample: NavSample);
    /// Queues a sighting for the world tables.
    fn sighting(&mut self, s: Sighting) -> bool;
    /// Queues a request for the periodic task.
    fn control(&mut self, c: Control) -> bool;
    /// Queues a reply owed to a request that does not go to the periodic task (refused at the
    /// wire, or "busy"); the periodic task sends it.
    fn reply(&mut self, r: ReplyRepr) -> bool;
    /// Lockstep: the host says the firmware's time is now `time_ms`; run a period.
    fn tick(&mut self, time_ms: u64);
    /// Publishes the newest route (overwrites the previous one).
    fn route(&mut self, r: Route);
    /// The mission goal the periodic task flies to and its generation
    /// (`crate::planner::Planner::goal_generation`): the route layer follows it.
    fn goal(&mut self) -> (u32, Option<crate::math::Vec2>);
}

/// What the background dropped, for telemetry.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct BackgroundCounters {
    /// Sightings dropped because their queue was full.
    pub sightings_dropped: u32,
    /// Requests answered "busy": their queue was full.
    pub requests_busy: u32,
    /// Requests dropped without an answer: their queue and the reply ring were both full.
    pub requests_unanswered: u32,
    /// `Params` messages refused at the wire (the decoder counted them in its `bad_payload`;
    /// telemetry moves them to `bad_params`).
    pub params_refused: u32,
    /// `Mission`, `MissionCount`, `MissionItem`, `Survey`, `ChartObstacle` and `ChartClear`
    /// messages refused at the wire (moved from the decoder's `bad_payload` to `bad_mission`
    /// as above).
    pub mission_refused: u32,
    /// `Nav` messages refused at the wire (moved from `bad_payload` to `bad_nav`).
    pub nav_refused: u32,
    /// `ChartObstacle` messages the wire accepted but the world's checks refused
    /// (`ChartObstacleRepr::to_obstacle`): telemetry counts them in `bad_mission`.
    pub charts_refused: u32,
    /// Scanlines the extractor refused.
    pub scanlines_rejected: u32,
    /// Scanlines taken in (the periodic task watches it: a sonar gone quiet slows the vehicle).
    pub scanlines: u32,
    /// Bearing swept by those scanlines, mrad (saturating): the periodic task waits for the
    /// first full sweep before it moves.
    pub swept_mrad: u32,
    /// How far the head turned between them, mrad (saturating): the steps of lost scanlines
    /// too. `swept_mrad / head_mrad` over a turn is the share of pings that arrived.
    pub head_mrad: u32,
    /// Features extracted from scanlines.
    pub features_extracted: u32,
    /// Contacts refused when converted to table entries.
    pub contacts_rejected: u32,
    /// `Tick`s refused for going back in time (telemetry counts them in `rx_bad_payload`).
    pub ticks_refused: u32,
}

/// The decoder, the sonar extractor and the newest pose they need.
pub struct Background {
    decoder: Decoder,
    extractor: Extractor,
    pose: Option<Pose>,
    /// Set by the first `Tick`: firmware time is then the host's, and navigation is stamped
    /// with its own time of validity instead of its arrival.
    lockstep: bool,
    /// Time of the newest accepted `Tick`, ms.
    last_tick_ms: Option<u64>,
    /// Head bearing of the newest accepted scanline, rad.
    last_bearing: Option<f32>,
    /// Counters.
    pub counters: BackgroundCounters,
    contact_a_plus: f32,
}

impl Background {
    /// A background with the sonar extractor configured by `sonar` (refused with the reason if
    /// it is out of range, which `ExtractorConfig::default()` is not), and host contacts given
    /// repulsiveness `contact_a_plus`.
    pub fn new(sonar: ExtractorConfig, contact_a_plus: f32) -> Result<Self, ConfigError> {
        Ok(Background {
            decoder: Decoder::accepting(Direction::ToFirmware),
            extractor: Extractor::new(sonar)?,
            pose: None,
            lockstep: false,
            last_tick_ms: None,
            last_bearing: None,
            counters: BackgroundCounters::default(),
            contact_a_plus,
        })
    }

    /// Whether a `Tick` has come: firmware time is then the host's.
    pub fn lockstep(&self) -> bool {
        self.lockstep
    }

    /// The newest vehicle pose navigation gave (`None` before the first `Nav`).
    pub fn pose(&self) -> Option<Pose> {
        self.pose
    }

    /// A scanline from a sonar on its own port (the Ping360 driver), taken at `pose`: into the
    /// extractor, the evidence map `map` and the route layer `router`, as a `Scanline`
    /// message's would be.
    pub fn on_scanline(
        &mut self,
        scan: &Scanline<'_>,
        pose: Option<Pose>,
        sink: &mut impl BackgroundOutputs,
        map: Option<&EvidenceMap>,
        router: Option<&mut Router>,
    ) {
        scanline(
            &mut self.extractor,
            &mut self.last_bearing,
            &mut self.counters,
            scan,
            pose,
            sink,
            map,
            router,
        );
    }

    /// A navigation fix from another source (the autopilot's MAVLink stream), arrived at
    /// firmware time `now_ms`: taken exactly as a `Nav` message's (pose, periodic task, route
    /// layer). The caller checked it.
    pub fn on_nav(
        &mut self,
        nav: NavState,
        now_ms: u64,
        sink: &mut impl BackgroundOutputs,
        map: Option<&EvidenceMap>,
        router: Option<&mut Router>,
    ) {
        navigation(nav, now_ms, &mut self.pose, sink, map, router);
    }

    /// The decoder's counters.
    pub fn rx_counters(&self) -> &RxCounters {
        self.decoder.counters()
    }

    /// Feeds received bytes at firmware time `now_ms`. Stops right after a `Tick` frame (so
    /// the caller runs that period before later bytes land) and returns the bytes not yet fed.
    ///
    /// Scanlines also go into `map`, the evidence map shared with the periodic task (this is
    /// its only writer), when one is given; missions, charts, contacts and navigation into the
    /// route layer `router` (which replans on navigation, at most once per `replan_ms`).
    pub fn on_bytes<'b>(
        &mut self,
        bytes: &'b [u8],
        now_ms: u64,
        sink: &mut impl BackgroundOutputs,
        map: Option<&EvidenceMap>,
        mut router: Option<&mut Router>,
    ) -> &'b [u8] {
        let mut rest = bytes;
        while !rest.is_empty() {
            let (outcome, tail) = self.decoder.feed(rest);
            rest = tail;
            match outcome {
                Outcome::Frame(header, msg) => {
                    let tick = matches!(msg, Message::Tick(_));
                    if let Message::Tick(t) = msg {
                        // Lockstep time never goes backwards: such a tick is refused, counted,
                        // and not answered (a repeated tick, same time, is answered again).
                        if self.last_tick_ms.is_some_and(|last| t.time_ms < last) {
                            count_if(true, &mut self.counters.ticks_refused);
                            return rest;
                        }
                        self.last_tick_ms = Some(t.time_ms);
                    }
                    self.lockstep |= tick;
                    dispatch(
                        header,
                        msg,
                        now_ms,
                        self.lockstep,
                        &mut self.extractor,
                        router.as_deref_mut(),
                        (&mut self.pose, &mut self.last_bearing),
                        &mut self.counters,
                        self.contact_a_plus,
                        sink,
                        map,
                    );
                    if tick {
                        return rest;
                    }
                }
                Outcome::Error {
                    header: Some(h),
                    error,
                } if h.msg_type.direction() == Direction::ToFirmware => {
                    // A refused Nav or request is counted as a refusal of its kind (not among the
                    // unanswered frames' `rx_bad_payload`); a request still gets its typed reply.
                    if h.msg_type == MessageType::Nav {
                        count_if(true, &mut self.counters.nav_refused);
                    }
                    if is_request(h.msg_type) {
                        let c = &mut self.counters;
                        if h.msg_type == MessageType::Params {
                            count_if(true, &mut c.params_refused);
                        } else {
                            count_if(true, &mut c.mission_refused);
                        }
                        owe(sink, ReplyRepr::from_error(h, error), c);
                    }
                }
                Outcome::Consumed | Outcome::OverFull | Outcome::Error { .. } => {}
            }
        }
        rest
    }
}

fn is_request(t: MessageType) -> bool {
    use MessageType as T;
    matches!(
        t,
        T::Mission
            | T::Params
            | T::ChartObstacle
            | T::ChartClear
            | T::MissionCount
            | T::MissionItem
            | T::Survey
    )
}

/// Queues a reply owed outside the request queue; when the ring is full too the request goes
/// unanswered, counted.
fn owe(sink: &mut impl BackgroundOutputs, r: ReplyRepr, counters: &mut BackgroundCounters) {
    let ok = sink.reply(r);
    count_if(!ok, &mut counters.requests_unanswered);
}

/// Queues a request; a full queue answers "busy". `true` if it was queued (the request will be
/// applied), so side effects of a request (the route layer's) happen only then.
fn request(
    sink: &mut impl BackgroundOutputs,
    c: Control,
    counters: &mut BackgroundCounters,
) -> bool {
    if sink.control(c) {
        return true;
    }
    if sink.reply(ReplyRepr::busy(c.header())) {
        count_if(true, &mut counters.requests_busy);
    } else {
        count_if(true, &mut counters.requests_unanswered);
    }
    false
}

fn count_if(cond: bool, counter: &mut u32) {
    if cond {
        *counter = counter.saturating_add(1);
    }
}

/// A scanline into the extractor and the evidence map, at the vehicle pose `pose` (refused and
/// counted without one: it cannot be placed in the world); its stretches of structure into the
/// route layer too, for where the map does not reach (`crate::route`, "Beyond the map").
#[allow(clippy::too_many_arguments)]
fn scanline(
    extractor: &mut Extractor,
    last_bearing: &mut Option<f32>,
    counters: &mut BackgroundCounters,
    scan: &Scanline<'_>,
    pose: Option<Pose>,
    sink: &mut impl BackgroundOutputs,
    map: Option<&EvidenceMap>,
    mut router: Option<&mut Router>,
) {
    let Some(p) = pose else {
        count_if(true, &mut counters.scanlines_rejected);
        return;
    };
    let mut emitted = 0u32;
    let mut dropped = 0u32;
    let result = extractor.push_scanline_mapped(scan, p, map, &mut |f| {
        emitted = emitted.saturating_add(1);
        if let (Some(r), Some(_)) = (router.as_deref_mut(), map) {
            r.feature(&f);
        }
        let ok = sink.sighting(Sighting::Feature(f));
        count_if(!ok, &mut dropped);
        ok
    });
    count_if(result.is_err(), &mut counters.scanlines_rejected);
    if result.is_ok() {
        counters.scanlines = counters.scanlines.saturating_add(1);
        let step = scan.step_rad.abs();
        // Lost pings show as a longer turn since the last scanline (up to half a turn).
        let turn = last_bearing.map_or(step, |b| {
            crate::math::wrap_angle(scan.bearing_rad - b).abs()
        });
        *last_bearing = Some(scan.bearing_rad);
        counters.swept_mrad = counters.swept_mrad.saturating_add((step * 1000.0) as u32);
        counters.head_mrad = counters.head_mrad.saturating_add((turn * 1000.0) as u32);
    }
    counters.features_extracted = counters.features_extracted.saturating_add(emitted);
    counters.sightings_dropped = counters.sightings_dropped.saturating_add(dropped);
}

/// A navigation fix at `time_ms`: the pose for scanlines, the newest navigation for the
/// periodic task, and the route layer's turn.
fn navigation(
    nav: NavState,
    time_ms: u64,
    pose: &mut Option<Pose>,
    sink: &mut impl BackgroundOutputs,
    map: Option<&EvidenceMap>,
    router: Option<&mut Router>,
) {
    *pose = Some(Pose {
        position: nav.position,
        heading: nav.heading,
    });
    sink.nav(NavSample { nav, time_ms });
    // The slow part of the route layer runs here, at most once per `replan_ms`, to the
    // waypoint the periodic task flies to.
    if let Some(r) = router {
        let (generation, goal) = sink.goal();
        r.follow(generation, goal);
        if let Some(route) = r.on_nav(nav.position, time_ms, map) {
            sink.route(route);
        }
    }
}

#[allow(clippy::too_many_arguments)]
fn dispatch(
    header: crate::link::Header,
    msg: Message<'_>,
    now_ms: u64,
    lockstep: bool,
    extractor: &mut Extractor,
    mut router: Option<&mut Router>,
    (pose, last_bearing): (&mut Option<Pose>, &mut Option<f32>),
    counters: &mut BackgroundCounters,
    contact_a_plus: f32,
    sink: &mut impl BackgroundOutputs,
    map: Option<&EvidenceMap>,
) {
    match msg {
        Message::Nav(n) => {
            let time_ms = if lockstep { n.time_ms } else { now_ms };
            navigation(n.nav, time_ms, pose, sink, map, router);
        }
        Message::Scanline(scan) => {
            scanline(
                extractor,
                last_bearing,
                counters,
                &scan,
                *pose,
                sink,
                map,
                router,
            );
        }
        Message::Contacts(c) => {
            let time_ms = if lockstep { c.time_ms } else { now_ms };
            for contact in c.contacts.iter() {
                // A vehicle the host reports is not structure: the sonar path leaves out its
                // echoes (`crate::sonar::KnownVehicles`).
                if contact.kind == crate::link::ContactKind::Vehicle {
                    let shape = &contact.shape;
                    extractor.report_vehicle(
                        contact.id,
                        shape.center(),
                        shape.bounding_radius(),
                        contact.velocity,
                        time_ms,
                    );
                }
                let s = match contact.kind {
                    crate::link::ContactKind::Obstacle => contact
                        .to_obstacle(contact_a_plus, now_ms)
                        .map(Sighting::Obstacle),
                    crate::link::ContactKind::Vehicle => {
                        contact.to_agent(now_ms).map(Sighting::Agent)
                    }
                };
                if let (Ok(Sighting::Obstacle(o)), Some(r)) = (&s, router.as_deref_mut()) {
                    r.obstacle(&o.shape, o.velocity);
                }
                match s {
                    Ok(s) => {
                        let ok = sink.sighting(s);
                        count_if(!ok, &mut counters.sightings_dropped);
                    }
                    Err(_) => count_if(true, &mut counters.contacts_rejected),
                }
            }
        }
        // The route layer follows a request only once it is queued: one answered "busy"
        // changes nothing anywhere.
        Message::Mission(m) => {
            if let (true, Some(r)) = (request(sink, Control::Mission(header, m), counters), router)
            {
                r.set_goal(m.goal.is_finite().then_some(m.goal));
            }
        }
        Message::Params(p) => {
            // The periodic task answers for the parameters; the route layer takes its cell size
            // and the hull only from a set it will accept.
            let queued = request(sink, Control::Params(header, p), counters);
            if let (true, Some(r), Ok(())) = (queued, router, p.validate()) {
                r.set_params(&p);
            }
        }
        Message::ChartObstacle(c) => match c.to_obstacle(now_ms) {
            Ok(o) => {
                if let (true, Some(r)) =
                    (request(sink, Control::Chart(header, o), counters), router)
                {
                    r.obstacle(&o.shape, o.velocity);
                }
            }
            Err(e) => {
                count_if(true, &mut counters.charts_refused);
                owe(sink, ReplyRepr::from_object_error(header, e), counters);
            }
        },
        Message::ChartClear(c) => {
            // The route grid does not know which cells one chart entry made: all go (still
            // contacts are marked again as they are seen).
            let queued = request(sink, Control::ChartClear(header, c), counters);
            if let (true, Some(r)) = (queued, router) {
                r.forget_charts();
            }
        }
        // Waypoint missions reach the route layer through the periodic task's goal (`BackgroundOutputs::goal`),
        // once they are complete and accepted.
        Message::MissionCount(c) => {
            request(sink, Control::MissionCount(header, c), counters);
        }
        Message::MissionItem(i) => {
            request(sink, Control::MissionItem(header, i), counters);
        }
        Message::Survey(s) => {
            request(sink, Control::Survey(header, s), counters);
        }
        Message::Tick(t) => sink.tick(t.time_ms),
        // Firmware → host messages are refused by the decoder (Direction::ToFirmware).
        Message::Command(_)
        | Message::Telemetry(_)
        | Message::Reply(_)
        | Message::Log(_)
        | Message::Belief(_) => {}
    }
}
