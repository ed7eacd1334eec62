//! The firmware as an onboard computer beside an ArduSub autopilot and QGroundControl, over
//! MAVLink 2 on a serial line of its own (`crate::link::mavlink`).
//!
//! Two halves, like the runtime's:
//! - [`MavInbound`] (the background): frames from the line. The autopilot's `ATTITUDE` and
//!   `LOCAL_POSITION_NED` become the navigation state (`Background::on_nav`, exactly as a
//!   `Nav` message: a stream that stops is stale navigation and the same fail-safe holds);
//!   its `GPS_GLOBAL_ORIGIN` is kept for global mission items; a mission upload addressed to
//!   this component (`MISSION_COUNT`, `MISSION_ITEM_INT`) goes to the periodic half as
//!   [`MavMission`]s.
//! - [`MavOutbound`] (the periodic task, after each period): `SET_POSITION_TARGET_LOCAL_NED`
//!   with the commanded velocity and heading every period (a hold or all-stop is a zero
//!   velocity), `STATUSTEXT` when the mode changes, `HEARTBEAT` each second,
//!   `OBSTACLE_DISTANCE` (72 sectors of 5°, body frame) twice a second from what the firmware
//!   believes, and the mission protocol's requests and acknowledgement.
//!
//! **Frames.** MAVLink's local frame is NED (x north, y east, yaw clockwise from north); the
//! firmware's is x east, y north, headings counter-clockwise from east. So a position
//! (north, east) is the firmware's (east, north), and heading ψ = π/2 − yaw.

use ::mavlink::dialects::common::{
    MavAutopilot, MavDistanceSensor, MavFrame, MavMissionResult, MavModeFlag, MavSeverity,
    MavState, MavType, PositionTargetTypemask, ATTITUDE_DATA, GPS_GLOBAL_ORIGIN_DATA,
    HEARTBEAT_DATA, LOCAL_POSITION_NED_DATA, MISSION_ACK_DATA, MISSION_COUNT_DATA,
    MISSION_ITEM_INT_DATA, MISSION_REQUEST_INT_DATA, OBSTACLE_DISTANCE_DATA,
    SET_POSITION_TARGET_LOCAL_NED_DATA, STATUSTEXT_DATA,
};
use ::mavlink::{MavlinkVersion, MessageData};

use crate::link::mavlink::{emit_frame, Frame, Known, MavCounters, MavDecoder, MAX_FRAME};
use crate::math::{wrap_angle, Vec2, PI};
use crate::planner::{Command, HoldReason, Mode, NavState, Waypoint, MAX_COORD_M, MAX_WAYPOINTS};
use crate::route::Router;
use crate::sonar::EvidenceMap;
use crate::world::World;

use super::{Background, BackgroundOutputs, NavSample, Periodic};

/// Who is who on the MAVLink line.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct MavConfig {
    /// This firmware's system id: the vehicle's (ArduSub's `SYSID_THISMAV`, 1 by default).
    pub sysid: u8,
    /// This firmware's component id: `MAV_COMP_ID_ONBOARD_COMPUTER` (191).
    pub compid: u8,
    /// The autopilot's system and component ids (1, 1: `MAV_COMP_ID_AUTOPILOT1`): navigation
    /// is taken from it only, and set-points go to it.
    pub autopilot: (u8, u8),
    /// An `ATTITUDE` older than this does not give a `LOCAL_POSITION_NED` its heading, ms.
    pub attitude_max_age_ms: u32,
}

impl Default for MavConfig {
    fn default() -> Self {
        MavConfig {
            sysid: 1,
            compid: 191,
            autopilot: (1, 1),
            attitude_max_age_ms: 1000,
        }
    }
}

/// A step of a mission upload, from the background to the periodic task.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum MavMission {
    /// `MISSION_COUNT`: an upload of `count` items opens (`mission_type` 0 is a mission;
    /// fences and rally points are not taken).
    Count {
        /// Items to come.
        count: u16,
        /// The uploader's system and component ids.
        gcs: (u8, u8),
        /// MAV_MISSION_TYPE.
        mission_type: u8,
    },
    /// `MISSION_ITEM_INT` number `seq`, as a waypoint or why it cannot be one.
    Item {
        /// Its index.
        seq: u16,
        /// The uploader's ids.
        gcs: (u8, u8),
        /// The waypoint, or the mission result to refuse the upload with.
        waypoint: Result<Waypoint, MavMissionResult>,
    },
}

/// Earth radius for the local tangent plane round the origin, m (WGS-84's equatorial).
pub const EARTH_RADIUS_M: f32 = 6_378_137.0;
/// Metres of a great circle per 1e-7 degree (MAVLink's integer latitude and longitude unit).
const METRES_PER_E7_DEGREE: f32 = EARTH_RADIUS_M * core::f32::consts::PI / 180.0 * 1e-7;
/// `MAV_CMD_NAV_WAYPOINT`, the one mission command taken.
pub const NAV_WAYPOINT: u32 = 16;

/// The background's half: the decoder and what navigation needs.
#[derive(Clone, Debug)]
pub struct MavInbound {
    cfg: MavConfig,
    decoder: MavDecoder,
    /// The autopilot's newest yaw (rad, NED) and when it came, ms.
    yaw: Option<(f32, u64)>,
    /// `GPS_GLOBAL_ORIGIN`: latitude, longitude, 1e-7 degrees.
    origin: Option<(i32, i32)>,
    /// Upload steps the queue to the periodic task had no room for (the uploader resends).
    pub missions_dropped: u32,
}

impl MavInbound {
    /// A decoder for the line, with `cfg`'s ids.
    pub fn new(cfg: MavConfig) -> Self {
        MavInbound {
            cfg,
            decoder: MavDecoder::new(),
            yaw: None,
            origin: None,
            missions_dropped: 0,
        }
    }

    /// The decoder's counters (refusals by this bridge included).
    pub fn counters(&self) -> &MavCounters {
        self.decoder.counters()
    }

    /// The origin of the autopilot's local frame, if it has sent it.
    pub fn origin(&self) -> Option<(i32, i32)> {
        self.origin
    }

    /// Feeds bytes from the line at firmware time `now_ms`: navigation into `background` (and
    /// through it `sink`, the evidence `map`'s route layer `router`), upload steps into
    /// `missions` (`false`: no room; dropped and counted).
    #[allow(clippy::too_many_arguments)]
    pub fn on_bytes(
        &mut self,
        bytes: &[u8],
        now_ms: u64,
        background: &mut Background,
        sink: &mut impl BackgroundOutputs,
        map: Option<&EvidenceMap>,
        mut router: Option<&mut Router>,
        missions: &mut impl FnMut(MavMission) -> bool,
    ) {
        let mut rest = bytes;
        while !rest.is_empty() {
            let (used, frame) = self.decoder.feed(rest);
            rest = rest.get(used..).unwrap_or(&[]);
            let Some(f) = frame else { continue };
            let outcome = take(
                &self.cfg,
                &f,
                now_ms,
                (&mut self.yaw, &mut self.origin),
                &mut |nav| background.on_nav(nav, now_ms, sink, map, router.as_deref_mut()),
                missions,
            );
            match outcome {
                Taken::Used | Taken::NotOurs => {}
                Taken::Refused => self.decoder.count_refused(),
                Taken::NoRoom => self.missions_dropped = self.missions_dropped.saturating_add(1),
            }
        }
    }
}

/// The autopilot's newest yaw (rad, NED) and when it came (ms).
type Yaw = (f32, u64);
/// `GPS_GLOBAL_ORIGIN`'s latitude and longitude, 1e-7 degrees.
type Origin = (i32, i32);

/// What became of a frame.
enum Taken {
    Used,
    /// From someone else, or for someone else.
    NotOurs,
    Refused,
    NoRoom,
}

/// One kept frame.
fn take(
    cfg: &MavConfig,
    f: &Frame<'_>,
    now_ms: u64,
    (yaw, origin): (&mut Option<Yaw>, &mut Option<Origin>),
    nav: &mut impl FnMut(NavState),
    missions: &mut impl FnMut(MavMission) -> bool,
) -> Taken {
    let v = MavlinkVersion::V2;
    let from_autopilot = (f.sysid, f.compid) == cfg.autopilot;
    let ok = |b: bool| if b { Taken::Used } else { Taken::Refused };
    match f.message {
        Known::Heartbeat => ok(HEARTBEAT_DATA::deser(v, f.payload).is_ok()),
        Known::Attitude if from_autopilot => match ATTITUDE_DATA::deser(v, f.payload) {
            Ok(a) if a.yaw.is_finite() && a.yaw.abs() <= 2.0 * PI => {
                *yaw = Some((a.yaw, now_ms));
                Taken::Used
            }
            _ => Taken::Refused,
        },
        Known::LocalPositionNed if from_autopilot => {
            let Ok(p) = LOCAL_POSITION_NED_DATA::deser(v, f.payload) else {
                return Taken::Refused;
            };
            let fresh = yaw
                .filter(|(_, t)| now_ms.saturating_sub(*t) <= u64::from(cfg.attitude_max_age_ms));
            match (fresh, nav_state(&p)) {
                (Some((y, _)), Some(mut n)) => {
                    n.heading = wrap_angle(PI / 2.0 - y);
                    nav(n);
                    Taken::Used
                }
                _ => Taken::Refused,
            }
        }
        Known::GpsGlobalOrigin if from_autopilot => {
            match GPS_GLOBAL_ORIGIN_DATA::deser(v, f.payload) {
                Ok(o) if o.latitude.abs() <= 900_000_000 && o.longitude.abs() <= 1_800_000_000 => {
                    *origin = Some((o.latitude, o.longitude));
                    Taken::Used
                }
                _ => Taken::Refused,
            }
        }
        Known::MissionCount => match MISSION_COUNT_DATA::deser(v, f.payload) {
            Ok(c) if (c.target_system, c.target_component) == (cfg.sysid, cfg.compid) => {
                // `mission_type` is an extension (byte 4): absent means 0, a mission.
                let mission_type = f.payload.get(4).copied().unwrap_or(0);
                let m = MavMission::Count {
                    count: c.count,
                    gcs: (f.sysid, f.compid),
                    mission_type,
                };
                if missions(m) {
                    Taken::Used
                } else {
                    Taken::NoRoom
                }
            }
            Ok(_) => Taken::NotOurs,
            Err(_) => Taken::Refused,
        },
        Known::MissionItemInt => match MISSION_ITEM_INT_DATA::deser(v, f.payload) {
            Ok(i) if (i.target_system, i.target_component) == (cfg.sysid, cfg.compid) => {
                let m = MavMission::Item {
                    seq: i.seq,
                    gcs: (f.sysid, f.compid),
                    waypoint: waypoint(&i, *origin),
                };
                if missions(m) {
                    Taken::Used
                } else {
                    Taken::NoRoom
                }
            }
            Ok(_) => Taken::NotOurs,
            // An unknown command or frame: the definitions do not have it.
            Err(_) => Taken::Refused,
        },
        _ => Taken::NotOurs,
    }
}

/// A `LOCAL_POSITION_NED` in the firmware's frame (heading set by the caller), if every value
/// is a number within the planner's bounds.
fn nav_state(p: &LOCAL_POSITION_NED_DATA) -> Option<NavState> {
    let position = Vec2::new(p.y, p.x);
    let velocity = Vec2::new(p.vy, p.vx);
    let sane = position.is_finite()
        && velocity.is_finite()
        && position.x.abs() <= MAX_COORD_M
        && position.y.abs() <= MAX_COORD_M
        && velocity.norm() <= 50.0;
    sane.then_some(NavState {
        position,
        heading: 0.0,
        velocity,
    })
}

/// A mission item as a waypoint: `MAV_CMD_NAV_WAYPOINT` only; in `MAV_FRAME_LOCAL_NED`
/// (x, y in 1e-4 m) or a global frame (1e-7 degrees) converted on the tangent plane at the
/// autopilot's `GPS_GLOBAL_ORIGIN` (an equirectangular projection: under 1 cm of error per
/// kilometre of the ±100 km the planner takes; in `f32`, the M4F's precision, whose rounding
/// at 100 km is under 1 cm). `param2` is the acceptance radius, m (0: the
/// planner's `arrival_radius`). Altitude is not used (ArduSub keeps its depth).
pub fn waypoint(
    i: &MISSION_ITEM_INT_DATA,
    origin: Option<(i32, i32)>,
) -> Result<Waypoint, MavMissionResult> {
    if i.command as u32 != NAV_WAYPOINT {
        return Err(MavMissionResult::MAV_MISSION_UNSUPPORTED);
    }
    let (north, east) = match i.frame as u32 {
        // MAV_FRAME_LOCAL_NED
        1 => (i.x as f32 * 1e-4, i.y as f32 * 1e-4),
        // MAV_FRAME_GLOBAL, _RELATIVE_ALT, _INT, _RELATIVE_ALT_INT, _TERRAIN_ALT, _TERRAIN_ALT_INT
        0 | 3 | 5 | 6 | 10 | 11 => {
            let Some((lat0, lon0)) = origin else {
                return Err(MavMissionResult::MAV_MISSION_ERROR);
            };
            if i.x.abs() > 900_000_000 {
                return Err(MavMissionResult::MAV_MISSION_INVALID_PARAM5_X);
            }
            if i.y.abs() > 1_800_000_000 {
                return Err(MavMissionResult::MAV_MISSION_INVALID_PARAM6_Y);
            }
            // Differences taken in integers, so f32 (the M4F's FPU) only scales them; the
            // longitude's wrapped into −180° ..= 180° by a turn either way (no 64-bit division).
            let dlon = match i64::from(i.y) - i64::from(lon0) {
                d if d >= 1_800_000_000 => d - 3_600_000_000,
                d if d < -1_800_000_000 => d + 3_600_000_000,
                d => d,
            };
            let dlat = i64::from(i.x) - i64::from(lat0);
            let lat0_rad = (lat0 as f32 * 1e-7).to_radians();
            let north = dlat as f32 * METRES_PER_E7_DEGREE;
            let east = dlon as f32 * METRES_PER_E7_DEGREE * crate::math::cos(lat0_rad);
            (north, east)
        }
        _ => return Err(MavMissionResult::MAV_MISSION_UNSUPPORTED_FRAME),
    };
    let p = Vec2::new(east, north);
    if !p.is_finite() || p.x.abs() > MAX_COORD_M || p.y.abs() > MAX_COORD_M {
        return Err(MavMissionResult::MAV_MISSION_INVALID_PARAM5_X);
    }
    if i.param2 == 0.0 {
        Ok(Waypoint::with_parameter_radius(p))
    } else {
        Waypoint::new(p, i.param2).map_err(|_| MavMissionResult::MAV_MISSION_INVALID_PARAM2)
    }
}

/// The upload in progress, on the periodic side.
#[derive(Clone, Copy, Debug)]
struct Uploading {
    gcs: (u8, u8),
    next: u16,
    asked_ms: u64,
    asks: u8,
}

/// A request unanswered this long is sent again, ms (the protocol's default item timeout).
pub const ITEM_TIMEOUT_MS: u64 = 1000;
/// Requests for one item before the upload is given up (cancelled, acknowledged so).
pub const ITEM_TRIES: u8 = 5;
/// `OBSTACLE_DISTANCE`'s range: 0.1 m ..= 30 m, in cm.
pub const OBSTACLE_MIN_CM: u16 = 10;
/// The farthest distance reported, cm (the sonar's default range); a sector with nothing
/// believed nearer is `OBSTACLE_MAX_CM + 1`, "no obstacle" by the message's definition.
pub const OBSTACLE_MAX_CM: u16 = 3000;
/// Sectors of `OBSTACLE_DISTANCE`, and their width, degrees.
pub const SECTORS: usize = 72;
const SECTOR_DEG: f32 = 5.0;

/// The periodic task's half: what goes out on the line.
#[derive(Clone, Debug)]
pub struct MavOutbound {
    cfg: MavConfig,
    seq: u8,
    last_mode: Option<Mode>,
    heartbeat_s: Option<u32>,
    obstacles_at: Option<u32>,
    upload: Option<Uploading>,
    /// Frames the transmit queue had no room for.
    pub frames_dropped: u32,
}

impl MavOutbound {
    /// The sender, with `cfg`'s ids.
    pub fn new(cfg: MavConfig) -> Self {
        MavOutbound {
            cfg,
            seq: 0,
            last_mode: None,
            heartbeat_s: None,
            obstacles_at: None,
            upload: None,
            frames_dropped: 0,
        }
    }

    /// After the period at `now_ms` that sent `cmd`: the upload steps `missions` has, then the
    /// set-point, and what is due of the status, heartbeat and obstacle distances, through
    /// `tx` (one whole frame each; `false`: no room, dropped and counted).
    pub fn on_period(
        &mut self,
        now_ms: u64,
        cmd: &Command,
        periodic: &mut Periodic,
        missions: &mut impl FnMut() -> Option<MavMission>,
        tx: &mut impl FnMut(&[u8]) -> bool,
    ) {
        for _ in 0..4 {
            let Some(m) = missions() else { break };
            self.mission(now_ms, m, periodic, tx);
        }
        self.resend(now_ms, tx);
        self.setpoint(now_ms, cmd, tx);
        if self.last_mode != Some(cmd.mode) && cmd.mode != Mode::Guarded {
            self.last_mode = Some(cmd.mode);
            let (severity, text) = describe(cmd.mode);
            self.status(severity, text, tx);
        }
        // In 32 bits: a 64-bit division would link the 1 KiB of compiler_builtins' u64 divider
        // into the image, and the count wraps only every 49 days (one early beat).
        let ms = now_ms as u32;
        if self.heartbeat_s != Some(ms / 1000) {
            self.heartbeat_s = Some(ms / 1000);
            let hb = HEARTBEAT_DATA {
                custom_mode: 0,
                mavtype: MavType::MAV_TYPE_ONBOARD_CONTROLLER,
                autopilot: MavAutopilot::MAV_AUTOPILOT_INVALID,
                base_mode: MavModeFlag::empty(),
                system_status: MavState::MAV_STATE_ACTIVE,
                mavlink_version: 3,
            };
            self.send(&hb, &[], tx);
        }
        if self.obstacles_at != Some(ms / 500) {
            self.obstacles_at = Some(ms / 500);
            if let Some(n) = periodic.nav() {
                self.obstacle_distance(now_ms, periodic.world(), &n, tx);
            }
        }
    }

    /// Sends `msg` and then `extension` bytes after its whole base payload.
    fn send<D: MessageData>(
        &mut self,
        msg: &D,
        extension: &[u8],
        tx: &mut impl FnMut(&[u8]) -> bool,
    ) {
        let mut payload = [0u8; 255];
        let _ = msg.ser(MavlinkVersion::V2, &mut payload);
        let mut len = D::ENCODED_LEN;
        for &b in extension {
            if let Some(slot) = payload.get_mut(len) {
                *slot = b;
                len += 1;
            }
        }
        let mut frame = [0u8; MAX_FRAME];
        let sent = payload
            .get(..len)
            .and_then(|p| {
                emit_frame(
                    self.seq,
                    (self.cfg.sysid, self.cfg.compid),
                    (D::ID, D::EXTRA_CRC),
                    p,
                    &mut frame,
                )
            })
            .and_then(|n| frame.get(..n))
            .is_some_and(tx);
        self.seq = self.seq.wrapping_add(1);
        if !sent {
            self.frames_dropped = self.frames_dropped.saturating_add(1);
        }
    }

    /// The command as a velocity and heading target in the autopilot's local frame; a hold
    /// is a zero velocity at the held heading.
    fn setpoint(&mut self, now_ms: u64, cmd: &Command, tx: &mut impl FnMut(&[u8]) -> bool) {
        let v = match cmd.mode {
            Mode::Hold(_) => Vec2::ZERO,
            _ => cmd.velocity,
        };
        let v = if v.is_finite() { v } else { Vec2::ZERO };
        let sp = SET_POSITION_TARGET_LOCAL_NED_DATA {
            time_boot_ms: now_ms as u32,
            vx: v.y,
            vy: v.x,
            vz: 0.0,
            yaw: wrap_angle(PI / 2.0 - cmd.psi_set),
            // Velocity and yaw: position, acceleration and yaw rate ignored.
            type_mask: PositionTargetTypemask::from_bits_truncate(SETPOINT_TYPE_MASK),
            target_system: self.cfg.autopilot.0,
            target_component: self.cfg.autopilot.1,
            coordinate_frame: MavFrame::MAV_FRAME_LOCAL_NED,
            ..SET_POSITION_TARGET_LOCAL_NED_DATA::default()
        };
        self.send(&sp, &[], tx);
    }

    fn status(&mut self, severity: MavSeverity, text: &str, tx: &mut impl FnMut(&[u8]) -> bool) {
        let st = STATUSTEXT_DATA {
            severity,
            text: text.into(),
        };
        self.send(&st, &[], tx);
    }

    /// One upload step.
    fn mission(
        &mut self,
        now_ms: u64,
        m: MavMission,
        periodic: &mut Periodic,
        tx: &mut impl FnMut(&[u8]) -> bool,
    ) {
        match m {
            MavMission::Count {
                count,
                gcs,
                mission_type,
            } => {
                let result = if mission_type != 0 {
                    Some(MavMissionResult::MAV_MISSION_UNSUPPORTED)
                } else if count == 0 || usize::from(count) > MAX_WAYPOINTS {
                    Some(MavMissionResult::MAV_MISSION_NO_SPACE)
                } else {
                    None
                };
                if let Some(r) = result {
                    self.upload = None;
                    return self.ack(gcs, r, tx);
                }
                periodic.open_upload(count as u8);
                self.upload = Some(Uploading {
                    gcs,
                    next: 0,
                    asked_ms: now_ms,
                    asks: 1,
                });
                self.request(gcs, 0, tx);
            }
            MavMission::Item { seq, gcs, waypoint } => {
                let Some(mut u) = self.upload.filter(|u| u.gcs == gcs) else {
                    return self.ack(gcs, MavMissionResult::MAV_MISSION_DENIED, tx);
                };
                if seq != u.next {
                    // A resend of one already stored, or out of order: ask for the one due.
                    return self.request(gcs, u.next, tx);
                }
                let stored = waypoint.and_then(|w| {
                    periodic
                        .upload_item(seq as u8, w)
                        .map_err(|_| MavMissionResult::MAV_MISSION_INVALID)
                });
                match stored {
                    Err(r) => {
                        self.upload = None;
                        self.ack(gcs, r, tx);
                        self.status(
                            MavSeverity::MAV_SEVERITY_WARNING,
                            "vpf: mission refused",
                            tx,
                        );
                    }
                    Ok(true) => {
                        self.upload = None;
                        self.ack(gcs, MavMissionResult::MAV_MISSION_ACCEPTED, tx);
                        self.status(MavSeverity::MAV_SEVERITY_INFO, "vpf: mission accepted", tx);
                    }
                    Ok(false) => {
                        u.next += 1;
                        u.asked_ms = now_ms;
                        u.asks = 1;
                        self.upload = Some(u);
                        self.request(gcs, u.next, tx);
                    }
                }
            }
        }
    }

    /// Asks again for an item not answered within [`ITEM_TIMEOUT_MS`]; gives up after
    /// [`ITEM_TRIES`].
    fn resend(&mut self, now_ms: u64, tx: &mut impl FnMut(&[u8]) -> bool) {
        let Some(mut u) = self.upload else { return };
        if now_ms.saturating_sub(u.asked_ms) < ITEM_TIMEOUT_MS {
            return;
        }
        if u.asks >= ITEM_TRIES {
            self.upload = None;
            return self.ack(u.gcs, MavMissionResult::MAV_MISSION_OPERATION_CANCELLED, tx);
        }
        u.asks += 1;
        u.asked_ms = now_ms;
        self.upload = Some(u);
        self.request(u.gcs, u.next, tx);
    }

    fn request(&mut self, gcs: (u8, u8), seq: u16, tx: &mut impl FnMut(&[u8]) -> bool) {
        let r = MISSION_REQUEST_INT_DATA {
            seq,
            target_system: gcs.0,
            target_component: gcs.1,
        };
        self.send(&r, &[], tx);
    }

    fn ack(&mut self, gcs: (u8, u8), result: MavMissionResult, tx: &mut impl FnMut(&[u8]) -> bool) {
        let a = MISSION_ACK_DATA {
            target_system: gcs.0,
            target_component: gcs.1,
            mavtype: result,
        };
        self.send(&a, &[], tx);
    }

    /// `OBSTACLE_DISTANCE` in the body frame (FRD: sector i is 5·i degrees clockwise from the
    /// bow) from the tables: [`sectors`].
    fn obstacle_distance(
        &mut self,
        now_ms: u64,
        world: &World,
        nav: &NavSample,
        tx: &mut impl FnMut(&[u8]) -> bool,
    ) {
        let od = OBSTACLE_DISTANCE_DATA {
            time_usec: now_ms.saturating_mul(1000),
            distances: sectors(world, &nav.nav),
            min_distance: OBSTACLE_MIN_CM,
            max_distance: OBSTACLE_MAX_CM,
            sensor_type: MavDistanceSensor::MAV_DISTANCE_SENSOR_ULTRASOUND,
            increment: SECTOR_DEG as u8,
        };
        // Extensions: increment_f, angle_offset (f32), frame (MAV_FRAME_BODY_FRD = 12).
        let mut ext = [0u8; 9];
        let (inc, rest) = ext.split_at_mut(4);
        inc.copy_from_slice(&SECTOR_DEG.to_le_bytes());
        if let Some(f) = rest.get_mut(4) {
            *f = MavFrame::MAV_FRAME_BODY_FRD as u8;
        }
        self.send(&od, &ext, tx);
    }
}

/// `type_mask`: ignore position (1, 2, 4), acceleration (64, 128, 256) and yaw rate (2048);
/// use velocity and yaw.
pub const SETPOINT_TYPE_MASK: u16 = 1 | 2 | 4 | 64 | 128 | 256 | 2048;

/// The nearest thing believed in each of the [`SECTORS`] body-frame sectors, cm: the evidence
/// map's cells the planner took this period (each a disc of half a cell) and the obstacle
/// table (each obstacle's surface distance over the sectors its bounding circle spans: the
/// nearest point of an obstacle stands for all of it, so a long wall seen obliquely reads
/// nearer than it is at its ends, never farther). Nothing within [`OBSTACLE_MAX_CM`]:
/// `OBSTACLE_MAX_CM + 1`.
pub fn sectors(world: &World, nav: &NavState) -> [u16; SECTORS] {
    let mut d = [OBSTACLE_MAX_CM + 1; SECTORS];
    let p = nav.position;
    let sector_rad = SECTOR_DEG.to_radians();
    let mut mark = |bearing: f32, half: f32, dist_m: f32| {
        if !(dist_m.is_finite() && bearing.is_finite()) {
            return;
        }
        let cm = (dist_m.max(0.0) * 100.0).clamp(f32::from(OBSTACLE_MIN_CM), 65_000.0) as u16;
        if cm > OBSTACLE_MAX_CM {
            return;
        }
        // Clockwise from the bow.
        let cw = -wrap_angle(bearing - nav.heading);
        // Every sector whose 5° touches the span.
        let span = libm::floorf((half + 0.5 * sector_rad) / sector_rad).min(36.0) as i32;
        let centre = libm::roundf(cw / sector_rad) as i32;
        for k in -span..=span {
            let i = (centre + k).rem_euclid(SECTORS as i32) as usize;
            if let Some(s) = d.get_mut(i) {
                *s = (*s).min(cm);
            }
        }
    };
    for c in world.map_cells() {
        let r = *c - p;
        mark(libm::atan2f(r.y, r.x), 0.0, r.norm() - 0.25);
    }
    for o in world.obstacles() {
        let r = o.shape.center() - p;
        let dist = r.norm();
        let radius = o.shape.bounding_radius();
        // asin(radius / dist) as an arc tangent: libm's `asinf` works in double precision,
        // software floating point on the Cortex-M4F.
        let half = if dist <= radius {
            PI
        } else {
            crate::math::atan2(radius, crate::math::sqrt(dist * dist - radius * radius))
        };
        mark(libm::atan2f(r.y, r.x), half, o.shape.signed_distance(p));
    }
    d
}

/// The status text for a mode, and its severity.
fn describe(mode: Mode) -> (MavSeverity, &'static str) {
    use MavSeverity::{MAV_SEVERITY_INFO as INFO, MAV_SEVERITY_WARNING as WARN};
    match mode {
        Mode::Hold(HoldReason::NoMission) => (INFO, "vpf: hold, no mission"),
        Mode::Hold(HoldReason::StaleNav) => (WARN, "vpf: hold, navigation stale"),
        Mode::Hold(HoldReason::InsideObstacle) => (WARN, "vpf: all-stop, inside an obstacle"),
        Mode::Hold(HoldReason::CollisionImminent) => (WARN, "vpf: all-stop, collision imminent"),
        Mode::Hold(HoldReason::FrozenNav) => (WARN, "vpf: hold, navigation frozen"),
        Mode::Hold(HoldReason::SonarBlind) => (WARN, "vpf: hold, sonar blind"),
        Mode::Transit => (INFO, "vpf: transit"),
        Mode::Escape => (INFO, "vpf: escape, ghost goal-point"),
        Mode::Arrived => (INFO, "vpf: arrived"),
        Mode::Loiter => (INFO, "vpf: loiter"),
        Mode::Guarded => (INFO, "vpf: guarded"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::field::Shape;
    use crate::world::{Obstacle, Origin};
    use ::mavlink::dialects::common::{MavCmd, MISSION_ITEM_INT_DATA};

    fn item(frame: u32, x: i32, y: i32) -> MISSION_ITEM_INT_DATA {
        let mut i = MISSION_ITEM_INT_DATA {
            command: MavCmd::MAV_CMD_NAV_WAYPOINT,
            x,
            y,
            param2: 2.0,
            ..MISSION_ITEM_INT_DATA::default()
        };
        i.frame = match frame {
            1 => MavFrame::MAV_FRAME_LOCAL_NED,
            6 => MavFrame::MAV_FRAME_GLOBAL_RELATIVE_ALT,
            _ => MavFrame::MAV_FRAME_BODY_FRD,
        };
        i
    }

    #[test]
    fn mission_items_become_waypoints_in_the_firmwares_frame() {
        // (MAV_FRAME_GLOBAL_RELATIVE_ALT, 3, stands for the global frames: QGroundControl and
        // the test script send its deprecated `_INT` twin, 6, which `waypoint` takes the same.)
        // Local NED: 10 m north, 3 m east → (3, 10).
        let w = waypoint(&item(1, 100_000, 30_000), None).unwrap();
        assert!((w.position() - Vec2::new(3.0, 10.0)).norm() < 1e-4, "{w:?}");
        assert_eq!(w.radius_m(), 2.0);
        // Global: 1e-4° of latitude north of the origin is 11.13 m; 1e-4° of longitude east at
        // 45° is 7.87 m.
        let origin = Some((450_000_000, 140_000_000));
        let w = waypoint(&item(6, 450_001_000, 140_001_000), origin).unwrap();
        assert_eq!(item(6, 0, 0).frame as u32, 3);
        assert!((w.position().y - 11.132).abs() < 0.01, "{w:?}");
        assert!((w.position().x - 7.871).abs() < 0.01, "{w:?}");
        // Refused, by name: no origin yet, a frame or a command it does not fly, bad values.
        let refused = |i, o| waypoint(&i, o).unwrap_err();
        assert_eq!(
            refused(item(6, 0, 0), None),
            MavMissionResult::MAV_MISSION_ERROR
        );
        assert_eq!(
            refused(item(12, 0, 0), None),
            MavMissionResult::MAV_MISSION_UNSUPPORTED_FRAME
        );
        let mut loiter = item(1, 0, 0);
        loiter.command = MavCmd::MAV_CMD_NAV_LOITER_UNLIM;
        assert_eq!(
            refused(loiter, None),
            MavMissionResult::MAV_MISSION_UNSUPPORTED
        );
        assert_eq!(
            refused(item(6, 950_000_000, 0), origin),
            MavMissionResult::MAV_MISSION_INVALID_PARAM5_X
        );
        let mut bad_radius = item(1, 0, 0);
        bad_radius.param2 = -1.0;
        assert_eq!(
            refused(bad_radius, None),
            MavMissionResult::MAV_MISSION_INVALID_PARAM2
        );
        // Beyond the planner's ±100 km.
        assert_eq!(
            refused(item(1, i32::MAX, 0), None),
            MavMissionResult::MAV_MISSION_INVALID_PARAM5_X
        );
    }

    #[test]
    fn navigation_needs_numbers_within_bounds() {
        let ok = LOCAL_POSITION_NED_DATA {
            x: 10.0,
            y: -4.0,
            vx: 0.5,
            vy: 0.0,
            ..LOCAL_POSITION_NED_DATA::default()
        };
        let n = nav_state(&ok).unwrap();
        assert_eq!(
            (n.position, n.velocity),
            (Vec2::new(-4.0, 10.0), Vec2::new(0.0, 0.5))
        );
        for bad in [
            LOCAL_POSITION_NED_DATA { x: f32::NAN, ..ok },
            LOCAL_POSITION_NED_DATA { y: 2e5, ..ok },
            LOCAL_POSITION_NED_DATA { vx: 80.0, ..ok },
        ] {
            assert_eq!(nav_state(&bad), None, "{bad:?}");
        }
    }

    #[test]
    fn obstacle_sectors_are_clockwise_from_the_bow() {
        let mut world = World::new();
        // A rock 5 m east of a vehicle heading north (ψ = π/2): 90° clockwise, sector 18.
        let rock = Shape::circle(Vec2::new(5.0, 0.0), 1.0).unwrap();
        world
            .upsert_obstacle(Obstacle::new(1, rock, 2.5, Origin::Charted, 0).unwrap())
            .unwrap();
        let nav = NavState {
            position: Vec2::ZERO,
            heading: PI / 2.0,
            velocity: Vec2::ZERO,
        };
        let d = sectors(&world, &nav);
        assert_eq!(d[18], 400);
        // Its circle spans ±11.5°: sectors 16 ..= 20; nothing elsewhere.
        for (i, &v) in d.iter().enumerate() {
            let expect = if (16..=20).contains(&i) {
                400
            } else {
                OBSTACLE_MAX_CM + 1
            };
            assert_eq!(v, expect, "sector {i}: {d:?}");
        }
    }
}
