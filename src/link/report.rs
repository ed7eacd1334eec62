//! Reports, firmware → host: `Command`, `Telemetry`, `Reply` and `Log`.

use super::codec::{angle, finite, refuse, within, Reader, Writer};
use super::control::param_index;
use super::decoder::RxCounters;
use super::frame::{Direction, Header, MessageType};
use super::message::Payload;
use super::{Error, Problem, MAX_LOG_LEN};
use crate::params::ParamProblem;
use crate::planner::{
    Command, FormationError, HoldReason, MissionProgress, Mode, PidSetpoints, StepError,
    MAX_GHOSTS, MAX_NAV_SPEED, MAX_WAYPOINTS,
};
use crate::sonar::ping360::Ping360Counters;
use crate::world::{ObjectError, MAX_AGENTS, MAX_OBSTACLES};

/// The wire codes of a [`Mode`]: (mode, hold reason). Mode 0 hold, 1 transit, 2 escape,
/// 3 arrived, 4 guarded, 5 loiter; hold reason 0 none (any mode but hold), 1 no mission, 2 stale navigation,
/// 3 inside an obstacle, 4 collision imminent.
pub const fn mode_codes(mode: Mode) -> (u8, u8) {
    match mode {
        Mode::Hold(r) => (
            0,
            match r {
                HoldReason::NoMission => 1,
                HoldReason::StaleNav => 2,
                HoldReason::InsideObstacle => 3,
                HoldReason::CollisionImminent => 4,
                HoldReason::FrozenNav => 5,
                HoldReason::SonarBlind => 6,
            },
        ),
        Mode::Transit => (1, 0),
        Mode::Escape => (2, 0),
        Mode::Arrived => (3, 0),
        Mode::Guarded => (4, 0),
        Mode::Loiter => (5, 0),
    }
}

/// The [`Mode`] of wire codes (mode, reason) in rows `mode_row` and `mode_row + 1`.
fn mode_from_codes(mode: u8, reason: u8, mode_row: u8) -> Result<Mode, Error> {
    let reason_row = mode_row + 1;
    let m = match mode {
        0 => Mode::Hold(match reason {
            1 => HoldReason::NoMission,
            2 => HoldReason::StaleNav,
            3 => HoldReason::InsideObstacle,
            4 => HoldReason::CollisionImminent,
            5 => HoldReason::FrozenNav,
            6 => HoldReason::SonarBlind,
            _ => return refuse(reason_row, Problem::UnknownCode),
        }),
        1 => Mode::Transit,
        2 => Mode::Escape,
        3 => Mode::Arrived,
        4 => Mode::Guarded,
        5 => Mode::Loiter,
        _ => return refuse(mode_row, Problem::UnknownCode),
    };
    if mode != 0 && reason != 0 {
        return refuse(reason_row, Problem::Invalid);
    }
    Ok(m)
}

/// `Command` payload length.
pub const COMMAND_LEN: usize = 71;

/// `Command` (0x81): one planner period's output, the whole [`Command`].
///
/// Layout (71 bytes): 0 `time_ms` u64 · 1 `psi_set` f32 (rad, ±2π) · 2 `v_set` f32 (m/s,
/// 0 ..= 20) · 3 `a_c` · 4 `v_c` · 5 `i_surge` · 6 `alpha_c` · 7 `omega_c` · 8 `phi_c` (rad,
/// ±2π) · 9 `target_x` · 10 `target_y` · 11 `clearance_m` (may be +∞) · 12 `force_x` ·
/// 13 `force_y` · 14 `velocity_x` · 15 `velocity_y` (all f32) · 16 `mode` u8 ·
/// 17 `hold_reason` u8 · 18 `ghost_depth` u8 (0 ..= `MAX_GHOSTS`).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct CommandRepr {
    /// The period's time, ms (firmware time).
    pub time_ms: u64,
    /// The command.
    pub command: Command,
}

impl CommandRepr {
    fn check(&self) -> Result<(), Error> {
        let c = &self.command;
        let s = &c.setpoints;
        angle(1, c.psi_set)?;
        within(2, c.v_set, 0.0, MAX_NAV_SPEED)?;
        finite(3, s.a_c)?;
        finite(4, s.v_c)?;
        finite(5, s.i_surge)?;
        finite(6, s.alpha_c)?;
        finite(7, s.omega_c)?;
        angle(8, s.phi_c)?;
        finite(9, c.target.x)?;
        finite(10, c.target.y)?;
        // +∞ is a valid clearance: nothing in the world.
        if c.clearance_m.is_nan() || c.clearance_m == f32::NEG_INFINITY {
            return refuse(11, Problem::NonFinite);
        }
        finite(12, c.force.x)?;
        finite(13, c.force.y)?;
        finite(14, c.velocity.x)?;
        finite(15, c.velocity.y)?;
        if usize::from(c.ghost_depth) > MAX_GHOSTS {
            return refuse(18, Problem::OutOfRange);
        }
        Ok(())
    }
}

impl<'a> Payload<'a> for CommandRepr {
    const TYPE: MessageType = MessageType::Command;

    fn parse(payload: &'a [u8]) -> Result<Self, Error> {
        let mut r = Reader::new(payload);
        let time_ms = r.u64()?;
        let psi_set = r.f32()?;
        let v_set = r.f32()?;
        let setpoints = PidSetpoints {
            a_c: r.f32()?,
            v_c: r.f32()?,
            i_surge: r.f32()?,
            alpha_c: r.f32()?,
            omega_c: r.f32()?,
            phi_c: r.f32()?,
        };
        let target = r.vec2()?;
        let clearance_m = r.f32()?;
        let force = r.vec2()?;
        let velocity = r.vec2()?;
        let mode = r.u8()?;
        let reason = r.u8()?;
        let ghost_depth = r.u8()?;
        r.finish()?;
        let repr = CommandRepr {
            time_ms,
            command: Command {
                psi_set,
                v_set,
                setpoints,
                mode: mode_from_codes(mode, reason, 16)?,
                force,
                velocity,
                target,
                ghost_depth,
                clearance_m,
            },
        };
        repr.check()?;
        Ok(repr)
    }

    fn payload_len(&self) -> usize {
        COMMAND_LEN
    }

    fn emit(&self, out: &mut [u8]) -> Result<usize, Error> {
        self.check()?;
        let c = &self.command;
        let s = &c.setpoints;
        let mut w = Writer::new(out);
        w.u64(self.time_ms)?;
        for v in [
            c.psi_set, c.v_set, s.a_c, s.v_c, s.i_surge, s.alpha_c, s.omega_c, s.phi_c,
        ] {
            w.f32(v)?;
        }
        w.vec2(c.target)?;
        w.f32(c.clearance_m)?;
        w.vec2(c.force)?;
        w.vec2(c.velocity)?;
        let (mode, reason) = mode_codes(c.mode);
        w.u8(mode)?;
        w.u8(reason)?;
        w.u8(c.ghost_depth)?;
        Ok(w.len())
    }
}

/// What `Telemetry::step_cost` counts.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[repr(u8)]
pub enum CostUnit {
    /// Not measured.
    Unknown = 0,
    /// Microseconds of wall-clock time.
    Microseconds = 1,
    /// CPU clock cycles (e.g. the Cortex-M DWT cycle counter).
    Cycles = 2,
    /// Instructions retired (e.g. in an emulator).
    Instructions = 3,
}

impl CostUnit {
    /// The unit with wire code `code`, if any.
    pub const fn from_code(code: u8) -> Option<CostUnit> {
        match code {
            0 => Some(CostUnit::Unknown),
            1 => Some(CostUnit::Microseconds),
            2 => Some(CostUnit::Cycles),
            3 => Some(CostUnit::Instructions),
            _ => None,
        }
    }
}

/// The firmware's counters since boot, each a saturating u32, in wire order.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct TelemetryCounters {
    /// Frames received and accepted.
    pub rx_frames: u32,
    /// Frames refused for a CRC mismatch.
    pub rx_crc_errors: u32,
    /// Frames dropped for exceeding the longest frame of their framing.
    pub rx_oversize: u32,
    /// Frames refused for bad COBS, a coded frame's impossible length, or being shorter than
    /// header and CRC.
    pub rx_framing_errors: u32,
    /// Frames refused for an unknown version, type or direction.
    pub rx_unknown: u32,
    /// Scanline, Contacts and Tick frames whose payload was refused (length or a field), and
    /// `Tick`s back in time. Requests refused at the wire count in `bad_params` /
    /// `bad_mission`, Nav in `bad_nav`.
    pub rx_bad_payload: u32,
    /// Nav messages refused: at the wire (length or a field), by the planner, or stamped more
    /// than a second ahead of its time.
    pub bad_nav: u32,
    /// Params messages refused, at the wire (a non-finite number, an unknown code, the length)
    /// or by the planner (a range): each once, here and nowhere else.
    pub bad_params: u32,
    /// Mission, ChartObstacle and ChartClear messages refused for their content, at the wire or
    /// by the planner (a chart refused because the obstacle table is full counts in
    /// `table_full` instead).
    pub bad_mission: u32,
    /// Received bytes lost because the receive queue was full.
    pub rx_bytes_dropped: u32,
    /// Sonar features lost because the feature queue was full.
    pub features_dropped: u32,
    /// Frames not sent because the transmit queue was full.
    pub tx_frames_dropped: u32,
    /// Planner periods that overran their deadline.
    pub deadline_overruns: u32,
    /// Obstacles or agents refused because their table was full.
    pub table_full: u32,
    /// Sensed obstacles evicted from a full table by nearer ones.
    pub table_evicted: u32,
    /// Sonar features extracted.
    pub features_extracted: u32,
    /// Periods whose command the guard turned, slowed or stopped (after the sixteen above on
    /// the wire).
    pub guard_interventions: u32,
    /// Periods held because navigation had frozen.
    pub frozen_nav_holds: u32,
    /// Requests answered "busy" ([`ReplyStatus::Busy`]): the request queue was full, nothing
    /// changed, the host sends them again.
    pub requests_busy: u32,
    /// Requests dropped without an answer: the request queue and the ring of owed replies were
    /// both full (more requests between two periods than `REQUESTS_PER_PERIOD`).
    pub requests_unanswered: u32,
    /// Frames whose wrong bytes the forward error correction repaired (version 7, row 37; they
    /// passed their CRC after it).
    pub rx_fec_corrected: u32,
    /// Frames with more wrong bytes than the forward error correction repairs, refused
    /// (version 7, row 38).
    pub rx_fec_uncorrectable: u32,
}

/// Number of counters in [`TelemetryCounters`]'s first block (rows 2 ..= 17); the guard's, the
/// frozen-navigation and the two request counters follow the byte fields (rows 24 ..= 27).
pub const TELEMETRY_COUNTERS: usize = 16;

impl TelemetryCounters {
    /// The counters in wire order.
    pub const fn to_array(&self) -> [u32; TELEMETRY_COUNTERS] {
        [
            self.rx_frames,
            self.rx_crc_errors,
            self.rx_oversize,
            self.rx_framing_errors,
            self.rx_unknown,
            self.rx_bad_payload,
            self.bad_nav,
            self.bad_params,
            self.bad_mission,
            self.rx_bytes_dropped,
            self.features_dropped,
            self.tx_frames_dropped,
            self.deadline_overruns,
            self.table_full,
            self.table_evicted,
            self.features_extracted,
        ]
    }

    /// The counters from wire order.
    pub const fn from_array(a: [u32; TELEMETRY_COUNTERS]) -> Self {
        let [rx_frames, rx_crc_errors, rx_oversize, rx_framing_errors, rx_unknown, rx_bad_payload, bad_nav, bad_params, bad_mission, rx_bytes_dropped, features_dropped, tx_frames_dropped, deadline_overruns, table_full, table_evicted, features_extracted] =
            a;
        TelemetryCounters {
            rx_frames,
            rx_crc_errors,
            rx_oversize,
            rx_framing_errors,
            rx_unknown,
            rx_bad_payload,
            bad_nav,
            bad_params,
            bad_mission,
            rx_bytes_dropped,
            features_dropped,
            tx_frames_dropped,
            deadline_overruns,
            table_full,
            table_evicted,
            features_extracted,
            guard_interventions: 0,
            frozen_nav_holds: 0,
            requests_busy: 0,
            requests_unanswered: 0,
            rx_fec_corrected: 0,
            rx_fec_uncorrectable: 0,
        }
    }

    /// Copies the stream decoder's counters into the `rx_*` fields.
    pub fn set_rx(&mut self, rx: &RxCounters) {
        self.rx_frames = rx.frames;
        self.rx_crc_errors = rx.crc;
        self.rx_oversize = rx.oversize;
        self.rx_framing_errors = rx.framing;
        self.rx_unknown = rx.version.saturating_add(rx.unknown_type);
        self.rx_bad_payload = rx.bad_payload;
        self.rx_fec_corrected = rx.corrected;
        self.rx_fec_uncorrectable = rx.uncorrectable;
    }
}

/// `Telemetry` payload length: 98 bytes, the mission progress block (rows 28 ..= 30, 6 bytes),
/// the Ping360 block (rows 31 ..= 36) and the forward error correction's two counters (rows
/// 37, 38).
pub const TELEMETRY_LEN: usize = 104 + 4 * Ping360Counters::COUNT + 8;
/// The row of the first mission-progress field.
pub const TELEMETRY_MISSION_ROW: u8 = 28;
/// Row of the first Ping360 counter in `Telemetry`.
pub const TELEMETRY_PING360_ROW: u8 = 31;

/// `Telemetry` (0x82): health and counters, sent periodically.
///
/// Layout (136 bytes): 0 `time_ms` u64 · 1 `step_cost` u32 · 2..=17 the sixteen u32 counters
/// of [`TelemetryCounters`] in declaration order · 18 `mode` u8 · 19 `hold_reason` u8 ·
/// 20 `obstacles` u8 (table fill, ≤ `MAX_OBSTACLES`) · 21 `agents` u8 (≤ `MAX_AGENTS`) ·
/// 22 `ghost_depth` u8 (≤ `MAX_GHOSTS`) · 23 `cost_unit` u8 ([`CostUnit`]) ·
/// 24 `guard_interventions` u32 · 25 `frozen_nav_holds` u32 · 26 `requests_busy` u32 ·
/// 27 `requests_unanswered` u32 · then the **mission progress block**:
/// 28 `mission_waypoint` u8 (the waypoint flown to, 0-based; = count once complete) ·
/// 29 `mission_waypoints` u8 (count, ≤ `MAX_WAYPOINTS`; 0: no mission) · 30 `mission_to_go_m`
/// f32 (m along the remaining waypoints, finite, ≥ 0) · 31..=36 the Ping360 port's six u32
/// counters of [`Ping360Counters`] in declaration order (all 0 where no Ping360 is driven) ·
/// 37 `rx_fec_corrected` u32 · 38 `rx_fec_uncorrectable` u32 (version 7).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct TelemetryRepr {
    /// Firmware time, ms.
    pub time_ms: u64,
    /// The planner's mode.
    pub mode: Mode,
    /// Obstacle table fill.
    pub obstacles: u8,
    /// Agent table fill.
    pub agents: u8,
    /// Stacked ghost goal-points.
    pub ghost_depth: u8,
    /// Cost of the last planner step, in `cost_unit`.
    pub step_cost: u32,
    /// What `step_cost` counts.
    pub cost_unit: CostUnit,
    /// Counters since boot.
    pub counters: TelemetryCounters,
    /// How far along its mission the vehicle is (all zero: no mission).
    pub mission: MissionProgress,
    /// The Ping360 port's counters since boot (rows 31 ..= 36; zero without a Ping360).
    pub ping360: Ping360Counters,
}

impl TelemetryRepr {
    fn check(&self) -> Result<(), Error> {
        let m = &self.mission;
        let row = TELEMETRY_MISSION_ROW;
        if usize::from(m.count) > MAX_WAYPOINTS {
            return refuse(row + 1, Problem::OutOfRange);
        }
        if m.current > m.count {
            return refuse(row, Problem::OutOfRange);
        }
        within(row + 2, m.to_go_m, 0.0, f32::MAX)?;
        if usize::from(self.obstacles) > MAX_OBSTACLES {
            return refuse(20, Problem::OutOfRange);
        }
        if usize::from(self.agents) > MAX_AGENTS {
            return refuse(21, Problem::OutOfRange);
        }
        if usize::from(self.ghost_depth) > MAX_GHOSTS {
            return refuse(22, Problem::OutOfRange);
        }
        Ok(())
    }
}

impl<'a> Payload<'a> for TelemetryRepr {
    const TYPE: MessageType = MessageType::Telemetry;

    fn parse(payload: &'a [u8]) -> Result<Self, Error> {
        let mut r = Reader::new(payload);
        let time_ms = r.u64()?;
        let step_cost = r.u32()?;
        let mut counters = [0u32; TELEMETRY_COUNTERS];
        for c in counters.iter_mut() {
            *c = r.u32()?;
        }
        let mode = r.u8()?;
        let reason = r.u8()?;
        let obstacles = r.u8()?;
        let agents = r.u8()?;
        let ghost_depth = r.u8()?;
        let unit = r.u8()?;
        let guard_interventions = r.u32()?;
        let frozen_nav_holds = r.u32()?;
        let requests_busy = r.u32()?;
        let requests_unanswered = r.u32()?;
        let mission = MissionProgress {
            current: r.u8()?,
            count: r.u8()?,
            to_go_m: r.f32()?,
        };
        let mut ping360 = [0u32; Ping360Counters::COUNT];
        for c in ping360.iter_mut() {
            *c = r.u32()?;
        }
        let rx_fec_corrected = r.u32()?;
        let rx_fec_uncorrectable = r.u32()?;
        r.finish()?;
        let t = TelemetryRepr {
            time_ms,
            mode: mode_from_codes(mode, reason, 18)?,
            obstacles,
            agents,
            ghost_depth,
            step_cost,
            cost_unit: CostUnit::from_code(unit).ok_or(Error::field(23, Problem::UnknownCode))?,
            counters: TelemetryCounters {
                guard_interventions,
                frozen_nav_holds,
                requests_busy,
                requests_unanswered,
                rx_fec_corrected,
                rx_fec_uncorrectable,
                ..TelemetryCounters::from_array(counters)
            },
            mission,
            ping360: Ping360Counters::from_array(ping360),
        };
        t.check()?;
        Ok(t)
    }

    fn payload_len(&self) -> usize {
        TELEMETRY_LEN
    }

    fn emit(&self, out: &mut [u8]) -> Result<usize, Error> {
        self.check()?;
        let mut w = Writer::new(out);
        w.u64(self.time_ms)?;
        w.u32(self.step_cost)?;
        self.counters
            .to_array()
            .iter()
            .try_for_each(|&c| w.u32(c))?;
        let (mode, reason) = mode_codes(self.mode);
        for b in [
            mode,
            reason,
            self.obstacles,
            self.agents,
            self.ghost_depth,
            self.cost_unit as u8,
        ] {
            w.u8(b)?;
        }
        w.u32(self.counters.guard_interventions)?;
        w.u32(self.counters.frozen_nav_holds)?;
        w.u32(self.counters.requests_busy)?;
        w.u32(self.counters.requests_unanswered)?;
        // Version 6: the mission progress block (rows 28–30), then the Ping360 block (rows 31–36).
        w.u8(self.mission.current)?;
        w.u8(self.mission.count)?;
        w.f32(self.mission.to_go_m)?;
        self.ping360.to_array().iter().try_for_each(|&c| w.u32(c))?;
        // Version 7: the forward error correction's counters (rows 37, 38).
        w.u32(self.counters.rx_fec_corrected)?;
        w.u32(self.counters.rx_fec_uncorrectable)?;
        Ok(w.len())
    }
}

/// The `field` of a rejection that concerns the message as a whole (its length, a full
/// table) rather than one field.
pub const FIELD_WHOLE_MESSAGE: u8 = 0xFF;

/// The verdict of a [`ReplyRepr`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ReplyStatus {
    /// The message was applied.
    Accepted,
    /// The message was refused; nothing changed.
    Rejected {
        /// The refused field's row in the message's layout table (for `Params`, the parameter
        /// index of [`PARAM_NAMES`](super::PARAM_NAMES)), or [`FIELD_WHOLE_MESSAGE`].
        field: u8,
        /// Why.
        problem: Problem,
    },
    /// The firmware's request queue was full: the message was not looked at and nothing
    /// changed; send it again after the next period's replies.
    Busy,
}

/// `Reply` (0x83, the "ParamsReply"): the firmware's answer to a `Params`, `Mission`,
/// `ChartObstacle` or `ChartClear` message, matched by type and sequence number.
///
/// Layout (6 bytes): 0 `to_type` u8 (a host → firmware type) · 1 `to_seq` u16 · 2 `status` u8
/// (0 accepted, 1 rejected, 2 busy) · 3 `field` u8 · 4 `problem` u8 ([`Problem`] code); `field`
/// and `problem` are 0 when accepted or busy.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ReplyRepr {
    /// Type of the message replied to.
    pub to_type: MessageType,
    /// Sequence number of the message replied to.
    pub to_seq: u16,
    /// Accepted, or why not.
    pub status: ReplyStatus,
}

impl ReplyRepr {
    /// The message with header `to` was applied.
    pub const fn accepted(to: Header) -> Self {
        ReplyRepr {
            to_type: to.msg_type,
            to_seq: to.seq,
            status: ReplyStatus::Accepted,
        }
    }

    /// The message with header `to` was refused for `problem` in `field`.
    pub const fn rejected(to: Header, field: u8, problem: Problem) -> Self {
        ReplyRepr {
            to_type: to.msg_type,
            to_seq: to.seq,
            status: ReplyStatus::Rejected { field, problem },
        }
    }

    /// The message with header `to` found the request queue full: not applied, send it again.
    pub const fn busy(to: Header) -> Self {
        ReplyRepr {
            to_type: to.msg_type,
            to_seq: to.seq,
            status: ReplyStatus::Busy,
        }
    }

    /// The message with header `to` failed to parse with `e` (from the decoder's
    /// [`Outcome::Error`](super::Outcome::Error)).
    pub const fn from_error(to: Header, e: Error) -> Self {
        match e {
            Error::Field { index, problem } => ReplyRepr::rejected(to, index, problem),
            _ => ReplyRepr::rejected(to, FIELD_WHOLE_MESSAGE, Problem::Invalid),
        }
    }

    /// The planner refused the `Params` or `Mission` message with header `to`
    /// ([`Planner::set_params`](crate::planner::Planner::set_params),
    /// [`Planner::set_mission`](crate::planner::Planner::set_mission)): names the parameter or
    /// mission field.
    pub fn from_step_error(to: Header, e: StepError) -> Self {
        let (field, problem) = match e {
            StepError::BadParams(pe) => (
                param_index(pe.name).unwrap_or(FIELD_WHOLE_MESSAGE),
                match pe.problem {
                    ParamProblem::NonFinite => Problem::NonFinite,
                    ParamProblem::OutOfRange => Problem::OutOfRange,
                },
            ),
            // The wire already refused non-finite goals: only the range is left.
            StepError::BadGoal => (0, Problem::OutOfRange),
            StepError::BadFormation(FormationError::Descriptor) => (3, Problem::UnknownCode),
            StepError::BadFormation(FormationError::NonFinite) => (2, Problem::NonFinite),
            StepError::BadFormation(FormationError::OutOfRange) => (2, Problem::OutOfRange),
            // Waypoint missions are checked at the wire, row by row (`super::mission`).
            StepError::BadNav | StepError::BadMission(_) => (FIELD_WHOLE_MESSAGE, Problem::Invalid),
            StepError::NonFinite => (FIELD_WHOLE_MESSAGE, Problem::NonFinite),
        };
        ReplyRepr::rejected(to, field, problem)
    }

    /// The world refused the `ChartObstacle` with header `to`
    /// ([`ChartObstacleRepr::to_obstacle`](super::ChartObstacleRepr::to_obstacle)): its
    /// `a_plus` (row 1).
    pub const fn from_object_error(to: Header, e: ObjectError) -> Self {
        let problem = match e {
            ObjectError::NonFinite => Problem::NonFinite,
            ObjectError::OutOfRange => Problem::OutOfRange,
        };
        ReplyRepr::rejected(to, 1, problem)
    }

    /// The obstacle table was full (charted obstacles are never evicted).
    pub const fn table_full(to: Header) -> Self {
        ReplyRepr::rejected(to, FIELD_WHOLE_MESSAGE, Problem::TableFull)
    }

    fn check(&self) -> Result<(), Error> {
        if self.to_type.direction() != Direction::ToFirmware {
            return refuse(0, Problem::Invalid);
        }
        Ok(())
    }
}

impl<'a> Payload<'a> for ReplyRepr {
    const TYPE: MessageType = MessageType::Reply;

    fn parse(payload: &'a [u8]) -> Result<Self, Error> {
        let mut r = Reader::new(payload);
        let to_type = r.u8()?;
        let to_seq = r.u16()?;
        let status = r.u8()?;
        let field = r.u8()?;
        let problem = r.u8()?;
        r.finish()?;
        let to_type =
            MessageType::from_code(to_type).ok_or(Error::field(0, Problem::UnknownCode))?;
        let status = match status {
            0 if field == 0 && problem == 0 => ReplyStatus::Accepted,
            0 => return refuse(3, Problem::Invalid),
            1 => ReplyStatus::Rejected {
                field,
                problem: Problem::from_code(problem)
                    .ok_or(Error::field(4, Problem::UnknownCode))?,
            },
            2 if field == 0 && problem == 0 => ReplyStatus::Busy,
            2 => return refuse(3, Problem::Invalid),
            _ => return refuse(2, Problem::UnknownCode),
        };
        let reply = ReplyRepr {
            to_type,
            to_seq,
            status,
        };
        reply.check()?;
        Ok(reply)
    }

    fn payload_len(&self) -> usize {
        6
    }

    fn emit(&self, out: &mut [u8]) -> Result<usize, Error> {
        self.check()?;
        let (status, field, problem) = match self.status {
            ReplyStatus::Accepted => (0, 0, 0),
            ReplyStatus::Rejected { field, problem } => (1, field, problem.code()),
            ReplyStatus::Busy => (2, 0, 0),
        };
        let mut w = Writer::new(out);
        w.u8(self.to_type.code())?;
        w.u16(self.to_seq)?;
        w.u8(status)?;
        w.u8(field)?;
        w.u8(problem)?;
        Ok(w.len())
    }
}

/// Severity of a [`LogRepr`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[repr(u8)]
pub enum LogLevel {
    /// Detail for debugging.
    Debug = 0,
    /// Normal events.
    Info = 1,
    /// Something unexpected, handled.
    Warn = 2,
    /// Something failed.
    Error = 3,
}

impl LogLevel {
    /// The level with wire code `code`, if any.
    pub const fn from_code(code: u8) -> Option<LogLevel> {
        match code {
            0 => Some(LogLevel::Debug),
            1 => Some(LogLevel::Info),
            2 => Some(LogLevel::Warn),
            3 => Some(LogLevel::Error),
            _ => None,
        }
    }
}

/// `Log` (0x84): a diagnostic text line.
///
/// Layout (1 + n bytes): 0 `level` u8 ([`LogLevel`]) · 1 `text`: the rest of the payload,
/// 0 ..= [`MAX_LOG_LEN`] bytes of UTF-8, no terminator.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct LogRepr<'a> {
    /// Severity.
    pub level: LogLevel,
    /// The text, at most [`MAX_LOG_LEN`] bytes.
    pub text: &'a str,
}

impl<'a> LogRepr<'a> {
    /// A log line with `text` cut to at most [`MAX_LOG_LEN`] bytes at a character boundary,
    /// so it can always be emitted.
    pub fn truncated(level: LogLevel, text: &'a str) -> Self {
        let mut end = text.len().min(MAX_LOG_LEN);
        while !text.is_char_boundary(end) {
            end -= 1;
        }
        LogRepr {
            level,
            text: text.get(..end).unwrap_or(""),
        }
    }
}

impl<'a> Payload<'a> for LogRepr<'a> {
    const TYPE: MessageType = MessageType::Log;

    fn parse(payload: &'a [u8]) -> Result<Self, Error> {
        let mut r = Reader::new(payload);
        let level = r.u8()?;
        let text = r.rest();
        let level = LogLevel::from_code(level).ok_or(Error::field(0, Problem::UnknownCode))?;
        if text.len() > MAX_LOG_LEN {
            return refuse(1, Problem::OutOfRange);
        }
        let text = core::str::from_utf8(text).map_err(|_| Error::field(1, Problem::Invalid))?;
        Ok(LogRepr { level, text })
    }

    fn payload_len(&self) -> usize {
        1 + self.text.len()
    }

    fn emit(&self, out: &mut [u8]) -> Result<usize, Error> {
        if self.text.len() > MAX_LOG_LEN {
            return refuse(1, Problem::OutOfRange);
        }
        let mut w = Writer::new(out);
        w.u8(self.level as u8)?;
        w.bytes(self.text.as_bytes())?;
        Ok(w.len())
    }
}

#[cfg(test)]
pub(crate) mod tests {
    extern crate std;
    use super::*;
    use crate::math::Vec2;
    use crate::params::ParamError;
    use proptest::prelude::*;
    use std::vec;

    fn hold_command(heading: f32) -> Command {
        Command::hold(HoldReason::NoMission, heading)
    }

    #[test]
    fn command_bytes() {
        let repr = CommandRepr {
            time_ms: 0x0102,
            command: Command {
                psi_set: 1.0,
                v_set: 0.5,
                setpoints: PidSetpoints {
                    a_c: 0.25,
                    v_c: 0.5,
                    i_surge: 0.0,
                    alpha_c: -1.0,
                    omega_c: 2.0,
                    phi_c: 1.0,
                },
                mode: Mode::Escape,
                force: Vec2::new(0.0, 1.0),
                velocity: Vec2::new(0.5, 0.0),
                target: Vec2::new(10.0, -5.0),
                ghost_depth: 2,
                clearance_m: f32::INFINITY,
            },
        };
        let mut want = std::vec![0x02, 0x01, 0, 0, 0, 0, 0, 0];
        for w in [
            [0x00, 0x00, 0x80, 0x3f], // psi_set 1
            [0x00, 0x00, 0x00, 0x3f], // v_set 0.5
            [0x00, 0x00, 0x80, 0x3e], // a_c 0.25
            [0x00, 0x00, 0x00, 0x3f], // v_c 0.5
            [0x00, 0x00, 0x00, 0x00], // i_surge 0
            [0x00, 0x00, 0x80, 0xbf], // alpha_c -1
            [0x00, 0x00, 0x00, 0x40], // omega_c 2
            [0x00, 0x00, 0x80, 0x3f], // phi_c 1
            [0x00, 0x00, 0x20, 0x41], // target_x 10
            [0x00, 0x00, 0xa0, 0xc0], // target_y -5
            [0x00, 0x00, 0x80, 0x7f], // clearance +inf
            [0x00, 0x00, 0x00, 0x00], // force_x
            [0x00, 0x00, 0x80, 0x3f], // force_y 1
            [0x00, 0x00, 0x00, 0x3f], // velocity_x 0.5
            [0x00, 0x00, 0x00, 0x00], // velocity_y
        ] {
            want.extend(w);
        }
        want.extend([2, 0, 2]); // escape, no hold reason, 2 ghosts
        assert_eq!(want.len(), COMMAND_LEN);
        let mut out = [0u8; COMMAND_LEN];
        assert_eq!(repr.emit(&mut out), Ok(COMMAND_LEN));
        assert_eq!(&out[..], &want[..]);
        assert_eq!(CommandRepr::parse(&want), Ok(repr));

        // The planner's hold command, with its infinite clearance, goes through.
        let hold = CommandRepr {
            time_ms: 3,
            command: hold_command(0.3),
        };
        let n = hold.emit(&mut out).unwrap();
        assert_eq!(&out[68..71], &[0, 1, 0]);
        assert_eq!(CommandRepr::parse(&out[..n]), Ok(hold));
    }

    #[test]
    fn command_refusals() {
        let mut out = [0u8; COMMAND_LEN];
        let good = CommandRepr {
            time_ms: 0,
            command: hold_command(0.0),
        };
        good.emit(&mut out).unwrap();
        let with = |off: usize, bytes: &[u8]| {
            let mut c = out;
            c[off..off + bytes.len()].copy_from_slice(bytes);
            CommandRepr::parse(&c)
        };
        assert_eq!(
            with(12, &(-1.0f32).to_le_bytes()),
            Err(Error::field(2, Problem::OutOfRange))
        );
        assert_eq!(
            with(48, &f32::NAN.to_le_bytes()),
            Err(Error::field(11, Problem::NonFinite))
        );
        assert_eq!(
            with(48, &f32::NEG_INFINITY.to_le_bytes()),
            Err(Error::field(11, Problem::NonFinite))
        );
        assert_eq!(with(68, &[6]), Err(Error::field(16, Problem::UnknownCode)));
        assert_eq!(
            with(68, &[0, 0]),
            Err(Error::field(17, Problem::UnknownCode))
        );
        assert_eq!(with(68, &[1, 2]), Err(Error::field(17, Problem::Invalid)));
        assert_eq!(with(70, &[5]), Err(Error::field(18, Problem::OutOfRange)));
        assert_eq!(CommandRepr::parse(&out[..70]), Err(Error::Length));
    }

    fn sample_telemetry() -> TelemetryRepr {
        TelemetryRepr {
            time_ms: 60_000,
            mode: Mode::Hold(HoldReason::StaleNav),
            obstacles: 3,
            agents: 1,
            ghost_depth: 0,
            step_cost: 1234,
            cost_unit: CostUnit::Cycles,
            counters: TelemetryCounters {
                guard_interventions: 17,
                frozen_nav_holds: 18,
                requests_busy: 19,
                requests_unanswered: 20,
                rx_fec_corrected: 37,
                rx_fec_uncorrectable: 38,
                ..TelemetryCounters::from_array(core::array::from_fn(|i| i as u32 + 1))
            },
            mission: MissionProgress {
                current: 2,
                count: 5,
                to_go_m: 40.0,
            },
            ping360: Ping360Counters::from_array(core::array::from_fn(|i| i as u32 + 21)),
        }
    }

    #[test]
    fn telemetry_bytes() {
        let t = sample_telemetry();
        let mut want = std::vec![0x60, 0xea, 0, 0, 0, 0, 0, 0]; // 60 000 ms
        want.extend([0xd2, 0x04, 0, 0]); // 1234
        for i in 1..=16u8 {
            want.extend([i, 0, 0, 0]);
        }
        want.extend([0, 2, 3, 1, 0, 2]);
        want.extend([17, 0, 0, 0, 18, 0, 0, 0, 19, 0, 0, 0, 20, 0, 0, 0]);
        want.extend([2, 5, 0x00, 0x00, 0x20, 0x42]); // waypoint 2 of 5, 40 m to go
                                                     // Rows 31..=36, the Ping360 port: data 21, commands 22, timeouts 23, checksum errors
                                                     // 24, malformed 25, bytes skipped 26.
        for i in 21..=26u8 {
            want.extend([i, 0, 0, 0]);
        }
        // Rows 37, 38: frames corrected 37, uncorrectable 38.
        want.extend([37, 0, 0, 0, 38, 0, 0, 0]);
        assert_eq!(want.len(), TELEMETRY_LEN);
        assert_eq!(TELEMETRY_LEN, 136);
        let mut out = [0u8; TELEMETRY_LEN];
        assert_eq!(t.emit(&mut out), Ok(TELEMETRY_LEN));
        assert_eq!(&out[..], &want[..]);
        assert_eq!(TelemetryRepr::parse(&want), Ok(t));
        assert_eq!(t.counters.rx_frames, 1);
        assert_eq!(t.counters.features_extracted, 16);
        assert_eq!(t.ping360.data, 21);
        assert_eq!(t.ping360.bytes_skipped, 26);

        let mut bad = want.clone();
        bad[78] = 33;
        assert_eq!(
            TelemetryRepr::parse(&bad),
            Err(Error::field(20, Problem::OutOfRange))
        );
        let mut bad = want.clone();
        bad[81] = 9;
        assert_eq!(
            TelemetryRepr::parse(&bad),
            Err(Error::field(23, Problem::UnknownCode))
        );
        let mut bad = want.clone();
        bad[98] = 6;
        assert_eq!(
            TelemetryRepr::parse(&bad),
            Err(Error::field(28, Problem::OutOfRange))
        );
        bad[99] = 17;
        assert_eq!(
            TelemetryRepr::parse(&bad),
            Err(Error::field(29, Problem::OutOfRange))
        );
        let mut bad = want.clone();
        bad[100..104].copy_from_slice(&f32::NAN.to_le_bytes());
        assert_eq!(
            TelemetryRepr::parse(&bad),
            Err(Error::field(30, Problem::NonFinite))
        );
    }

    #[test]
    fn telemetry_takes_the_decoders_counters() {
        let rx = RxCounters {
            frames: 10,
            crc: 2,
            oversize: 1,
            framing: 3,
            version: 4,
            unknown_type: 5,
            bad_payload: 6,
            uncorrectable: 7,
            corrected: 8,
        };
        let mut c = TelemetryCounters::default();
        c.set_rx(&rx);
        assert_eq!(&c.to_array()[..6], &[10, 2, 1, 3, 9, 6]);
        assert_eq!((c.rx_fec_corrected, c.rx_fec_uncorrectable), (8, 7));
    }

    #[test]
    fn reply_bytes_and_constructors() {
        let h = Header {
            msg_type: MessageType::Params,
            seq: 0x0304,
        };
        let ack = ReplyRepr::accepted(h);
        let mut out = [0u8; 6];
        assert_eq!(ack.emit(&mut out), Ok(6));
        assert_eq!(out, [0x07, 0x04, 0x03, 0, 0, 0]);
        assert_eq!(ReplyRepr::parse(&out), Ok(ack));

        let e = StepError::BadParams(ParamError {
            name: "v_max",
            problem: ParamProblem::OutOfRange,
        });
        let rej = ReplyRepr::from_step_error(h, e);
        rej.emit(&mut out).unwrap();
        assert_eq!(out, [0x07, 0x04, 0x03, 1, 5, 2]);
        assert_eq!(ReplyRepr::parse(&out), Ok(rej));

        let m = Header {
            msg_type: MessageType::Mission,
            seq: 1,
        };
        assert_eq!(
            ReplyRepr::from_step_error(m, StepError::BadFormation(FormationError::Descriptor))
                .status,
            ReplyStatus::Rejected {
                field: 3,
                problem: Problem::UnknownCode
            }
        );
        assert_eq!(
            ReplyRepr::from_error(m, Error::field(6, Problem::NonFinite)).status,
            ReplyStatus::Rejected {
                field: 6,
                problem: Problem::NonFinite
            }
        );
        ReplyRepr::table_full(m).emit(&mut out).unwrap();
        assert_eq!(out, [0x04, 0x01, 0x00, 1, 0xff, 5]);
        let busy = ReplyRepr::busy(m);
        busy.emit(&mut out).unwrap();
        assert_eq!(out, [0x04, 0x01, 0x00, 2, 0, 0]);
        assert_eq!(ReplyRepr::parse(&out), Ok(busy));

        // Refusals.
        assert_eq!(
            ReplyRepr::parse(&[0x81, 0, 0, 0, 0, 0]),
            Err(Error::field(0, Problem::Invalid))
        );
        assert_eq!(
            ReplyRepr::parse(&[0x42, 0, 0, 0, 0, 0]),
            Err(Error::field(0, Problem::UnknownCode))
        );
        assert_eq!(
            ReplyRepr::parse(&[7, 0, 0, 0, 1, 0]),
            Err(Error::field(3, Problem::Invalid))
        );
        assert_eq!(
            ReplyRepr::parse(&[7, 0, 0, 1, 1, 9]),
            Err(Error::field(4, Problem::UnknownCode))
        );
        assert_eq!(
            ReplyRepr::parse(&[7, 0, 0, 3, 0, 0]),
            Err(Error::field(2, Problem::UnknownCode))
        );
        assert_eq!(
            ReplyRepr::parse(&[7, 0, 0, 2, 0xff, 0]),
            Err(Error::field(3, Problem::Invalid))
        );
        let to_host = ReplyRepr::accepted(Header {
            msg_type: MessageType::Log,
            seq: 0,
        });
        assert_eq!(
            to_host.emit(&mut out),
            Err(Error::field(0, Problem::Invalid))
        );
    }

    #[test]
    fn log_bytes() {
        let l = LogRepr {
            level: LogLevel::Warn,
            text: "nav stale",
        };
        let mut out = [0u8; 100];
        assert_eq!(l.emit(&mut out), Ok(10));
        assert_eq!(&out[..10], b"\x02nav stale");
        assert_eq!(LogRepr::parse(&out[..10]), Ok(l));
        assert_eq!(
            LogRepr::parse(&[1, 0xff, 0xfe]),
            Err(Error::field(1, Problem::Invalid))
        );
        assert_eq!(
            LogRepr::parse(&[4]),
            Err(Error::field(0, Problem::UnknownCode))
        );
        assert_eq!(LogRepr::parse(&[]), Err(Error::Length));
        let long = [b'a'; 97];
        let mut p = std::vec![0u8];
        p.extend(long);
        assert_eq!(
            LogRepr::parse(&p),
            Err(Error::field(1, Problem::OutOfRange))
        );
        // Truncation respects character boundaries: 95 ASCII bytes + a 2-byte 'é' = 97.
        let s: std::string::String = "x".repeat(95) + "é";
        let t = LogRepr::truncated(LogLevel::Info, &s);
        assert_eq!(t.text.len(), 95);
        assert!(t.emit(&mut out).is_ok());
        let bad = LogRepr {
            level: LogLevel::Info,
            text: &s,
        };
        assert_eq!(
            bad.emit(&mut out),
            Err(Error::field(1, Problem::OutOfRange))
        );
    }

    pub(crate) fn arb_mode() -> impl Strategy<Value = Mode> {
        prop_oneof![
            Just(Mode::Transit),
            Just(Mode::Escape),
            Just(Mode::Arrived),
            Just(Mode::Guarded),
            Just(Mode::Loiter),
            Just(Mode::Hold(HoldReason::NoMission)),
            Just(Mode::Hold(HoldReason::StaleNav)),
            Just(Mode::Hold(HoldReason::InsideObstacle)),
            Just(Mode::Hold(HoldReason::CollisionImminent)),
            Just(Mode::Hold(HoldReason::FrozenNav)),
            Just(Mode::Hold(HoldReason::SonarBlind)),
        ]
    }

    pub(crate) fn arb_command() -> impl Strategy<Value = CommandRepr> {
        (
            any::<u64>(),
            proptest::array::uniform14(-1e3f32..1e3),
            0.0f32..20.0,
            prop_oneof![Just(f32::INFINITY), -10.0f32..1e3],
            arb_mode(),
            0u8..=MAX_GHOSTS as u8,
        )
            .prop_map(
                |(t, f, v_set, clearance_m, mode, ghost_depth)| CommandRepr {
                    time_ms: t,
                    command: Command {
                        psi_set: f[0] / 200.0,
                        v_set,
                        setpoints: PidSetpoints {
                            a_c: f[1],
                            v_c: f[2],
                            i_surge: f[3],
                            alpha_c: f[4],
                            omega_c: f[5],
                            phi_c: f[6] / 200.0,
                        },
                        mode,
                        force: Vec2::new(f[7], f[8]),
                        velocity: Vec2::new(f[9], f[10]),
                        target: Vec2::new(f[11], f[12]),
                        ghost_depth,
                        clearance_m,
                    },
                },
            )
    }

    pub(crate) fn arb_telemetry() -> impl Strategy<Value = TelemetryRepr> {
        (
            any::<u64>(),
            arb_mode(),
            (0u8..=32, 0u8..=8, 0u8..=4),
            any::<u32>(),
            0u8..4,
            proptest::array::uniform16(any::<u32>()),
            (0u8..=16, 0u8..=16, 0.0f32..1e6),
            proptest::array::uniform6(any::<u32>()),
        )
            .prop_map(
                |(t, mode, (o, a, g), cost, unit, c, (i, n, d), p)| TelemetryRepr {
                    time_ms: t,
                    mode,
                    obstacles: o,
                    agents: a,
                    ghost_depth: g,
                    step_cost: cost,
                    cost_unit: CostUnit::from_code(unit).unwrap(),
                    counters: TelemetryCounters::from_array(c),
                    mission: MissionProgress {
                        current: i.min(n),
                        count: n,
                        to_go_m: d,
                    },
                    ping360: Ping360Counters::from_array(p),
                },
            )
    }

    pub(crate) fn arb_reply() -> impl Strategy<Value = ReplyRepr> {
        (
            0usize..8,
            any::<u16>(),
            proptest::option::of((any::<u8>(), 1u8..=5)),
        )
            .prop_map(|(t, seq, rej)| ReplyRepr {
                to_type: MessageType::ALL[t],
                to_seq: seq,
                status: match rej {
                    None => ReplyStatus::Accepted,
                    Some((field, p)) => ReplyStatus::Rejected {
                        field,
                        problem: Problem::from_code(p).unwrap(),
                    },
                },
            })
    }

    /// Owned log fields: (level code, text of at most MAX_LOG_LEN bytes).
    pub(crate) fn arb_log() -> impl Strategy<Value = (u8, std::string::String)> {
        (
            0u8..4,
            proptest::collection::vec(any::<char>(), 0..40).prop_map(|cs| {
                let s: std::string::String = cs.into_iter().collect();
                LogRepr::truncated(LogLevel::Debug, &s).text.into()
            }),
        )
    }

    proptest! {
        #![proptest_config(ProptestConfig { failure_persistence: None, ..ProptestConfig::default() })]

        #[test]
        fn reports_round_trip(
            c in arb_command(),
            t in arb_telemetry(),
            r in arb_reply(),
            (level, text) in arb_log(),
        ) {
            let mut out = [0u8; 136];
            let n = c.emit(&mut out).unwrap();
            prop_assert_eq!(n, c.payload_len());
            prop_assert_eq!(CommandRepr::parse(&out[..n]), Ok(c));
            let n = t.emit(&mut out).unwrap();
            prop_assert_eq!(n, t.payload_len());
            prop_assert_eq!(TelemetryRepr::parse(&out[..n]), Ok(t));
            let n = r.emit(&mut out).unwrap();
            prop_assert_eq!(n, r.payload_len());
            prop_assert_eq!(ReplyRepr::parse(&out[..n]), Ok(r));
            let l = LogRepr { level: LogLevel::from_code(level).unwrap(), text: &text };
            let n = l.emit(&mut out).unwrap();
            prop_assert_eq!(n, l.payload_len());
            prop_assert_eq!(LogRepr::parse(&out[..n]), Ok(l));
        }

        #[test]
        fn report_parsers_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..120)) {
            let _ = CommandRepr::parse(&bytes);
            let _ = TelemetryRepr::parse(&bytes);
            let _ = ReplyRepr::parse(&bytes);
            let _ = LogRepr::parse(&bytes);
        }

        #[test]
        fn truncation_always_emits(s in ".{0,120}") {
            let l = LogRepr::truncated(LogLevel::Error, &s);
            prop_assert!(s.starts_with(l.text));
            prop_assert!(l.text.len() <= MAX_LOG_LEN);
            prop_assert!(l.text.len() + 4 > MAX_LOG_LEN.min(s.len()));
            let mut out = [0u8; 1 + MAX_LOG_LEN];
            prop_assert!(l.emit(&mut out).is_ok());
        }
    }
}
