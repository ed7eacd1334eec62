//! Requests over the wire (docs/protocol.md, issue 11 §5 and §6): every request gets exactly
//! one reply; a full request queue answers "busy" and counts it; a host that sends again what
//! was answered "busy" lands a whole start-up burst; every refusal is counted once, in the
//! counter of its kind. And waypoint missions (issue 12 §2): uploaded item by item, flown only
//! once complete; surveys expanded by the firmware.

use std::collections::HashMap;

use vpf::field::Shape;
use vpf::guidance::{
    OneThreadRuntime, RuntimeConfig, CONTROL_QUEUE, REPLY_QUEUE, REQUESTS_PER_PERIOD, TX_QUEUE,
};
use vpf::link::{
    encode_frame, ChartClearRepr, ChartObstacleRepr, CostUnit, Decoder, Direction, Message,
    MessageType, MissionCountRepr, MissionItemRepr, NavRepr, Outcome, Payload, Problem, ReplyRepr,
    ReplyStatus, SurveyRepr, TelemetryRepr, TickRepr, FIELD_WHOLE_MESSAGE, MAX_FRAME,
};
use vpf::planner::{MissionEnd, Survey, Waypoint, Waypoints, MAX_WAYPOINTS};
use vpf::world::{Origin, MAX_OBSTACLES};
use vpf::{Mission, NavState, Params, Vec2};

/// A host talking to a [`OneThreadRuntime`] in lockstep, keeping what it sent by sequence number.
struct Host {
    fw: OneThreadRuntime,
    seq: u16,
    now_ms: u64,
    decoder: Decoder,
    replies: Vec<ReplyRepr>,
    telemetry: Vec<TelemetryRepr>,
    sent: HashMap<u16, Message<'static>>,
    /// The most bytes one call sent (a period's frames: what the board's transmit queue holds).
    most_out: usize,
}

impl Host {
    fn new() -> Self {
        let fw = OneThreadRuntime::new(
            Params::default(),
            RuntimeConfig::default(),
            CostUnit::Unknown,
        );
        Host {
            fw: fw.unwrap(),
            seq: 0,
            now_ms: 0,
            decoder: Decoder::accepting(Direction::ToHost),
            replies: vec![],
            telemetry: vec![],
            sent: HashMap::new(),
            most_out: 0,
        }
    }

    fn bytes(&mut self, bytes: &[u8]) {
        let mut out = Vec::new();
        self.fw.on_bytes(bytes, &mut || 0, &mut |f: &[u8]| {
            out.extend_from_slice(f);
            true
        });
        self.most_out = self.most_out.max(out.len());
        for b in out {
            if let Outcome::Frame(_, m) = self.decoder.push(b) {
                match m {
                    Message::Reply(r) => self.replies.push(r),
                    Message::Telemetry(t) => self.telemetry.push(t),
                    _ => {}
                }
            }
        }
    }

    fn next_seq(&mut self) -> u16 {
        self.seq = self.seq.wrapping_add(1);
        self.seq
    }

    /// Sends `m`; returns its sequence number.
    fn send(&mut self, m: Message<'static>) -> u16 {
        let seq = self.next_seq();
        let mut buf = [0u8; MAX_FRAME];
        let n = m.emit_frame(seq, &mut buf).unwrap();
        self.sent.insert(seq, m);
        self.bytes(&buf[..n]);
        seq
    }

    /// Sends a frame of type `t` with `payload` as it is (a host with a bug).
    fn send_raw(&mut self, t: MessageType, payload: &[u8]) -> u16 {
        let seq = self.next_seq();
        let mut buf = [0u8; MAX_FRAME];
        let n = encode_frame(
            t,
            seq,
            |b| {
                b[..payload.len()].copy_from_slice(payload);
                Ok(payload.len())
            },
            &mut buf,
        )
        .unwrap();
        self.bytes(&buf[..n]);
        seq
    }

    /// Runs the next period (100 ms on); returns the replies it brought.
    fn period(&mut self) -> Vec<ReplyRepr> {
        let before = self.replies.len();
        let t = self.now_ms;
        let nav = NavState {
            position: Vec2::ZERO,
            heading: 0.0,
            velocity: Vec2::ZERO,
        };
        self.send(Message::Nav(NavRepr {
            time_ms: t,
            nav,
            body: None,
        }));
        self.send(Message::Tick(TickRepr { time_ms: t }));
        self.now_ms += 100;
        self.replies[before..].to_vec()
    }

    fn last_telemetry(&self) -> TelemetryRepr {
        *self.telemetry.last().unwrap()
    }
}

fn chart(id: u16) -> Message<'static> {
    // A full table of rocks on a 4 × 8 grid well away from the vehicle.
    let x = 20.0 + 5.0 * f32::from(id % 8);
    let y = -10.0 + 5.0 * f32::from(id / 8);
    Message::ChartObstacle(ChartObstacleRepr {
        id,
        shape: Shape::circle(Vec2::new(x, y), 1.0).unwrap(),
        a_plus: 2.5,
    })
}

/// Parameters that differ from the defaults, so their arrival shows.
fn params() -> Params {
    Params {
        v_max: 1.5,
        ..Params::default()
    }
}

fn start_up_burst() -> Vec<Message<'static>> {
    let mut burst = vec![
        Message::Params(params()),
        Message::Mission(Mission {
            goal: Vec2::new(80.0, 0.0),
            formation: None,
        }),
    ];
    burst.extend((0..MAX_OBSTACLES as u16).map(chart));
    burst
}

/// Every sequence number in `seqs` is answered exactly once among `replies`.
fn answered_once(replies: &[ReplyRepr], seqs: &[u16]) {
    let mut count: HashMap<u16, usize> = HashMap::new();
    for r in replies {
        *count.entry(r.to_seq).or_default() += 1;
    }
    for s in seqs {
        assert_eq!(count.get(s), Some(&1), "request {s} answered once");
    }
    assert_eq!(replies.len(), seqs.len(), "no reply to anything else");
}

/// The start-up burst (parameters, mission, a full chart) between two periods: each request
/// gets one reply in the next period — the queue's worth applied, the rest "busy" and counted,
/// none lost. A host that sends the busy ones again, no more than the queue holds per period,
/// lands all of them.
#[test]
fn a_start_up_burst_is_answered_in_full_and_lands_when_paced() {
    let mut host = Host::new();
    host.period();
    let burst = start_up_burst();
    assert_eq!(burst.len(), REQUESTS_PER_PERIOD);
    let seqs: Vec<u16> = burst.iter().map(|m| host.send(*m)).collect();
    let replies = host.period();
    answered_once(&replies, &seqs);
    let busy: Vec<u16> = replies
        .iter()
        .filter(|r| r.status == ReplyStatus::Busy)
        .map(|r| r.to_seq)
        .collect();
    assert_eq!(busy.len(), REQUESTS_PER_PERIOD - CONTROL_QUEUE);
    // The queue keeps arrival order: the parameters and the mission went first and landed.
    let accepted: Vec<u16> = replies
        .iter()
        .filter(|r| r.status == ReplyStatus::Accepted)
        .map(|r| r.to_seq)
        .collect();
    assert_eq!(accepted, seqs[..CONTROL_QUEUE]);
    assert_eq!(host.fw.periodic().planner().params().v_max, 1.5);
    assert!(host.fw.periodic().planner().mission().is_some());
    let t = host.last_telemetry();
    assert_eq!(t.counters.requests_busy, busy.len() as u32);
    assert_eq!(t.counters.requests_unanswered, 0);
    // The period that answers the burst sends the most a period sends (every reply, command,
    // telemetry, belief): the board's transmit queue takes it whole, with room to spare.
    println!("the burst's period sent {} bytes", host.most_out);
    assert!(host.most_out < TX_QUEUE * 3 / 4, "{}", host.most_out);

    // Pacing: at most the queue's capacity in flight; what comes back "busy" goes again.
    let mut pending: Vec<Message<'static>> = busy.iter().map(|s| host.sent[s]).collect();
    let mut periods = 0;
    while !pending.is_empty() {
        let take = pending.len().min(CONTROL_QUEUE);
        let batch: Vec<u16> = pending.drain(..take).map(|m| host.send(m)).collect();
        let replies = host.period();
        answered_once(&replies, &batch);
        for r in &replies {
            match r.status {
                ReplyStatus::Accepted => {}
                ReplyStatus::Busy => pending.push(host.sent[&r.to_seq]),
                ReplyStatus::Rejected { .. } => panic!("refused: {r:?}"),
            }
        }
        periods += 1;
        assert!(periods <= MAX_OBSTACLES, "the chart never landed");
    }
    assert_eq!(
        periods,
        (REQUESTS_PER_PERIOD - CONTROL_QUEUE).div_ceil(CONTROL_QUEUE)
    );
    let world = host.fw.periodic().world();
    assert_eq!(world.obstacles().len(), MAX_OBSTACLES);
    assert!(world
        .obstacles()
        .iter()
        .all(|o| o.origin == Origin::Charted));
    let t = host.last_telemetry();
    assert_eq!(usize::from(t.obstacles), MAX_OBSTACLES);
    assert_eq!(
        t.counters.requests_busy,
        busy.len() as u32,
        "a paced host is never busy"
    );
    assert_eq!(t.counters.table_full, 0);
    assert_eq!(t.counters.bad_mission, 0);
}

/// The case: parameters, a mission and six charted obstacles in one go. Two periods
/// (the second for the busy ones, sent again) land all six.
#[test]
fn six_charted_obstacles_with_parameters_and_mission_all_land() {
    let mut host = Host::new();
    let mut burst = start_up_burst();
    burst.truncate(2 + 6);
    let seqs: Vec<u16> = burst.iter().map(|m| host.send(*m)).collect();
    let replies = host.period();
    answered_once(&replies, &seqs);
    let again: Vec<Message<'static>> = replies
        .iter()
        .filter(|r| r.status == ReplyStatus::Busy)
        .map(|r| host.sent[&r.to_seq])
        .collect();
    assert_eq!(again.len(), 8 - CONTROL_QUEUE);
    let seqs: Vec<u16> = again.into_iter().map(|m| host.send(m)).collect();
    let replies = host.period();
    answered_once(&replies, &seqs);
    assert!(replies.iter().all(|r| r.status == ReplyStatus::Accepted));
    assert_eq!(host.fw.periodic().world().obstacles().len(), 6);
}

/// Beyond the queue and the reply ring, requests go unanswered — counted, never silently.
#[test]
fn requests_beyond_the_queue_and_the_ring_are_counted_unanswered() {
    let mut host = Host::new();
    let extra = 3;
    let seqs: Vec<u16> = (0..REQUESTS_PER_PERIOD + extra)
        .map(|_| host.send(Message::ChartClear(ChartClearRepr::All)))
        .collect();
    let replies = host.period();
    assert_eq!(replies.len(), CONTROL_QUEUE + REPLY_QUEUE);
    answered_once(&replies, &seqs[..REQUESTS_PER_PERIOD]);
    let t = host.last_telemetry();
    assert_eq!(t.counters.requests_busy, REPLY_QUEUE as u32);
    assert_eq!(t.counters.requests_unanswered, extra as u32);
    // The next period has room again.
    let s = host.send(Message::ChartClear(ChartClearRepr::All));
    let replies = host.period();
    assert_eq!(replies.len(), 1);
    assert_eq!(
        (replies[0].to_seq, replies[0].status),
        (s, ReplyStatus::Accepted)
    );
}

/// A request answered "busy" changed nothing: the parameters stay until it is sent again.
#[test]
fn a_busy_request_changes_nothing() {
    let mut host = Host::new();
    for _ in 0..CONTROL_QUEUE {
        host.send(Message::ChartClear(ChartClearRepr::All));
    }
    let p = host.send(Message::Params(params()));
    let replies = host.period();
    let r = replies.iter().find(|r| r.to_seq == p).unwrap();
    assert_eq!(r.status, ReplyStatus::Busy);
    assert_eq!(host.fw.periodic().planner().params().v_max, 1.0);
    host.send(Message::Params(params()));
    let replies = host.period();
    assert_eq!(replies[0].status, ReplyStatus::Accepted);
    assert_eq!(host.fw.periodic().planner().params().v_max, 1.5);
}

/// One counter per kind of refusal: a Params or Mission refused at the wire is answered and
/// counted in `bad_params` / `bad_mission` (like one the planner refuses), not in
/// `rx_bad_payload`, which keeps the refused frames nobody answers (here a Contacts); a Nav
/// refused at the wire counts in `bad_nav`, with those the planner refuses.
#[test]
fn refusals_at_the_wire_count_as_refused_requests() {
    let mut host = Host::new();
    // Params with a NaN epsilon (row 1, bytes 4..8): the wire refuses non-finite numbers.
    let mut payload = [0u8; vpf::link::PARAMS_LEN];
    let n = Params::default().emit(&mut payload).unwrap();
    assert_eq!(n, payload.len());
    payload[4..8].copy_from_slice(&f32::NAN.to_le_bytes());
    let bad_params = host.send_raw(MessageType::Params, &payload);
    // A Mission a byte too long.
    let mut mission = [0u8; 10];
    Mission {
        goal: Vec2::new(5.0, 0.0),
        formation: None,
    }
    .emit(&mut mission)
    .unwrap();
    let bad_mission = host.send_raw(MessageType::Mission, &mission);
    // A chart with A⁺ out of range.
    let mut c = [0u8; 32];
    let n = ChartObstacleRepr {
        id: 7,
        shape: Shape::circle(Vec2::new(10.0, 0.0), 1.0).unwrap(),
        a_plus: 2.5,
    }
    .emit(&mut c)
    .unwrap();
    c[2..6].copy_from_slice(&500.0f32.to_le_bytes());
    let bad_chart = host.send_raw(MessageType::ChartObstacle, &c[..n]);
    // Parameters the planner refuses (a range): the same counter.
    let planner_refused = host.send(Message::Params(Params {
        v_max: 50.0,
        ..Params::default()
    }));
    let replies = host.period();
    answered_once(
        &replies,
        &[bad_params, bad_mission, bad_chart, planner_refused],
    );
    let status = |s: u16| replies.iter().find(|r| r.to_seq == s).unwrap().status;
    let rejected = |field, problem| ReplyStatus::Rejected { field, problem };
    assert_eq!(status(bad_params), rejected(1, Problem::NonFinite));
    assert_eq!(
        status(bad_mission),
        rejected(FIELD_WHOLE_MESSAGE, Problem::Invalid)
    );
    assert_eq!(status(bad_chart), rejected(1, Problem::OutOfRange));
    let v_max = vpf::link::param_index("v_max").unwrap();
    assert_eq!(
        status(planner_refused),
        rejected(v_max, Problem::OutOfRange)
    );
    let t = host.last_telemetry().counters;
    assert_eq!((t.bad_params, t.bad_mission, t.rx_bad_payload), (2, 2, 0));

    // A Nav a byte short: not answered, counted as refused navigation.
    host.send_raw(MessageType::Nav, &[0u8; 28]);
    host.period();
    let t = host.last_telemetry().counters;
    assert_eq!((t.bad_params, t.bad_mission, t.rx_bad_payload), (2, 2, 0));
    assert_eq!(t.bad_nav, 1);
    // A Contacts a byte short: not answered, counted with the refused frames.
    host.send_raw(MessageType::Contacts, &[0u8; 8]);
    host.period();
    let t = host.last_telemetry().counters;
    assert_eq!((t.rx_bad_payload, t.bad_nav), (1, 1));
}

fn waypoint(k: u8) -> Waypoint {
    // A zig-zag east: (10k, ±5), radius 2; every other leg at 0.6 m/s.
    let y = if k.is_multiple_of(2) { 5.0 } else { -5.0 };
    let speed = (!k.is_multiple_of(2)).then_some(0.6);
    Waypoint::new(Vec2::new(10.0 * f32::from(k + 1), y), 2.0)
        .and_then(|w| w.with_speed(speed))
        .unwrap()
}

/// Sends `burst` paced as docs/protocol.md §9 says (at most the queue's capacity in flight,
/// again what came back busy) and returns each request's final reply by its first sequence.
fn paced(host: &mut Host, burst: &[Message<'static>]) -> Vec<ReplyStatus> {
    let mut pending: Vec<(usize, Message<'static>)> = burst.iter().copied().enumerate().collect();
    let mut done = vec![None; burst.len()];
    for _ in 0..20 {
        if pending.is_empty() {
            break;
        }
        let take = pending.len().min(CONTROL_QUEUE);
        let batch: Vec<(usize, u16)> = pending
            .drain(..take)
            .map(|(i, m)| (i, host.send(m)))
            .collect();
        let replies = host.period();
        answered_once(&replies, &batch.iter().map(|b| b.1).collect::<Vec<_>>());
        for (i, seq) in batch {
            let r = replies.iter().find(|r| r.to_seq == seq).unwrap();
            match r.status {
                ReplyStatus::Busy => pending.push((i, burst[i])),
                s => done[i] = Some(s),
            }
        }
    }
    done.into_iter().map(Option::unwrap).collect()
}

/// A waypoint mission goes up as `MissionCount` and one `MissionItem` per waypoint (the queue's
/// slots stay small); until the last item lands the mission in force flies on; then the whole
/// list replaces it and telemetry shows the progress. Sent in one go, the queue answers the
/// overflow busy, and a paced host lands it all.
#[test]
fn a_waypoint_mission_goes_up_item_by_item_and_flies_only_when_complete() {
    let mut host = Host::new();
    host.period();
    let single = Mission {
        goal: Vec2::new(80.0, 0.0),
        formation: None,
    };
    assert_eq!(
        paced(&mut host, &[Message::Mission(single)]),
        [ReplyStatus::Accepted]
    );
    let n = MAX_WAYPOINTS as u8;
    let count = Message::MissionCount(MissionCountRepr {
        count: n,
        end: MissionEnd::Hold,
        formation: None,
    });
    let item = |k: u8| {
        Message::MissionItem(MissionItemRepr {
            index: k,
            waypoint: waypoint(k),
        })
    };
    // The count and all but the last item, in one go: four land, the rest come back busy.
    let mut burst = vec![count];
    burst.extend((0..n - 1).map(item));
    let seqs: Vec<u16> = burst.iter().map(|m| host.send(*m)).collect();
    let replies = host.period();
    answered_once(&replies, &seqs);
    let busy = replies
        .iter()
        .filter(|r| r.status == ReplyStatus::Busy)
        .count();
    assert_eq!(busy, burst.len() - CONTROL_QUEUE);
    // Paced, the rest land; the single goal is still flown.
    let again: Vec<Message<'static>> = replies
        .iter()
        .filter(|r| r.status == ReplyStatus::Busy)
        .map(|r| host.sent[&r.to_seq])
        .collect();
    assert!(paced(&mut host, &again)
        .iter()
        .all(|s| *s == ReplyStatus::Accepted));
    let planner = host.fw.periodic().planner();
    assert_eq!(planner.mission().unwrap().goal, single.goal);
    assert_eq!(host.last_telemetry().mission.count, 1);
    // The last item completes it: the list is flown from its first waypoint.
    assert_eq!(paced(&mut host, &[item(n - 1)]), [ReplyStatus::Accepted]);
    let planner = host.fw.periodic().planner();
    let flown = planner.waypoints().unwrap().clone();
    assert_eq!(flown.len(), MAX_WAYPOINTS);
    assert!(flown
        .as_slice()
        .iter()
        .zip(0..n)
        .all(|(w, k)| *w == waypoint(k)));
    assert_eq!(planner.mission().unwrap().goal, waypoint(0).position());
    host.period();
    let m = host.last_telemetry().mission;
    let to_go = flown.distance_to_go(Vec2::ZERO, 0);
    assert_eq!((m.current, m.count), (0, n));
    assert!((m.to_go_m - to_go).abs() < 1e-3, "{m:?} vs {to_go}");
    assert_eq!(host.last_telemetry().counters.bad_mission, 0);
}

/// Items that belong to no upload, or beyond its count, are refused (field 0, the index),
/// counted in `bad_mission`, and change nothing; a new `MissionCount` starts over.
#[test]
fn items_outside_an_upload_are_refused_and_counted() {
    let mut host = Host::new();
    let item = |k: u8| {
        Message::MissionItem(MissionItemRepr {
            index: k,
            waypoint: waypoint(k),
        })
    };
    let count = |n: u8| {
        Message::MissionCount(MissionCountRepr {
            count: n,
            end: MissionEnd::Loiter {
                radius_m: 10.0,
                clockwise: false,
            },
            formation: None,
        })
    };
    let rejected = |problem| ReplyStatus::Rejected { field: 0, problem };
    assert_eq!(paced(&mut host, &[item(0)]), [rejected(Problem::Invalid)]);
    let got = paced(&mut host, &[count(2), item(2), item(0)]);
    assert_eq!(
        got,
        [
            ReplyStatus::Accepted,
            rejected(Problem::OutOfRange),
            ReplyStatus::Accepted
        ]
    );
    assert!(host.fw.periodic().planner().mission().is_none());
    // Starting over forgets item 0: one more item does not complete it.
    let got = paced(&mut host, &[count(2), item(1)]);
    assert_eq!(got, [ReplyStatus::Accepted, ReplyStatus::Accepted]);
    assert!(host.fw.periodic().planner().mission().is_none());
    assert_eq!(paced(&mut host, &[item(0)]), [ReplyStatus::Accepted]);
    let flown = host.fw.periodic().planner().waypoints().unwrap().clone();
    assert_eq!(flown.len(), 2);
    assert!(matches!(flown.end(), MissionEnd::Loiter { .. }));
    // After completion the upload is closed again.
    assert_eq!(paced(&mut host, &[item(0)]), [rejected(Problem::Invalid)]);
    assert_eq!(host.last_telemetry().counters.bad_mission, 3);
}

/// A `Survey` is expanded by the firmware into the same list the library makes; one that does
/// not fit is refused on its spacing's row, counted, and the mission in force is kept.
#[test]
fn a_survey_is_expanded_by_the_firmware() {
    let mut host = Host::new();
    let survey = Survey {
        corner: Vec2::new(10.0, -20.0),
        length_m: 60.0,
        width_m: 30.0,
        heading: 0.3,
        spacing_m: 10.0,
        radius_m: 2.0,
        speed: Some(0.8),
    };
    let msg = |s: Survey| {
        Message::Survey(SurveyRepr {
            survey: s,
            end: MissionEnd::Hold,
            formation: None,
        })
    };
    assert_eq!(paced(&mut host, &[msg(survey)]), [ReplyStatus::Accepted]);
    let want = Waypoints::survey(&survey, MissionEnd::Hold).unwrap();
    assert_eq!(host.fw.periodic().planner().waypoints(), Some(&want));
    assert_eq!(want.len(), 8);
    // Nine lines: refused by the wire, on the spacing (row 5), and counted.
    let mut payload = [0u8; 64];
    let n = SurveyRepr {
        survey,
        end: MissionEnd::Hold,
        formation: None,
    }
    .emit(&mut payload)
    .unwrap();
    payload[20..24].copy_from_slice(&3.5f32.to_le_bytes());
    let s = host.send_raw(MessageType::Survey, &payload[..n]);
    let replies = host.period();
    answered_once(&replies, &[s]);
    assert_eq!(
        replies[0].status,
        ReplyStatus::Rejected {
            field: 5,
            problem: Problem::OutOfRange
        }
    );
    assert_eq!(host.fw.periodic().planner().waypoints(), Some(&want));
    assert_eq!(host.last_telemetry().counters.bad_mission, 1);
}
