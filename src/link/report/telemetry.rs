//! `Telemetry` (0x82): health and counters, sent periodically.

use super::field::telemetry;
use crate::link::codec::{finite, refuse, within, Reader, Writer};
use crate::link::counters::{Ping360Counters, TelemetryCounters, TELEMETRY_COUNTERS};
use crate::link::frame::MessageType;
use crate::link::modes::{mode_codes, mode_from_codes};
use crate::link::payload::Payload;
use crate::link::{Error, Problem};
use crate::math::Vec2;
use crate::params::MAX_GHOSTS;
use crate::types::{MissionProgress, Mode, MAX_WAYPOINTS};
use crate::world::{MAX_AGENTS, MAX_OBSTACLES};

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

/// `Telemetry` payload length: 98 bytes, the mission progress block (rows 28 ..= 30, 6 bytes),
/// the Ping360 block (rows 31 ..= 36), the forward error correction's two counters (rows
/// 37, 38) and the current (rows 39, 40).
pub const TELEMETRY_LEN: usize = 104 + 4 * Ping360Counters::COUNT + 8 + 8;
/// The row of the first mission-progress field.
pub const TELEMETRY_MISSION_ROW: u8 = telemetry::MISSION_WAYPOINT.row;
/// Row of the first Ping360 counter in `Telemetry`.
pub const TELEMETRY_PING360_ROW: u8 = telemetry::PING360_DATA.row;

/// `Telemetry` (0x82): health and counters, sent periodically.
///
/// Layout (144 bytes): 0 `time_ms` u64 · 1 `step_cost` u32 · 2..=17 the sixteen u32 counters
/// of [`TelemetryCounters`] in declaration order · 18 `mode` u8 · 19 `hold_reason` u8 ·
/// 20 `obstacles` u8 (table fill, ≤ `MAX_OBSTACLES`) · 21 `agents` u8 (≤ `MAX_AGENTS`) ·
/// 22 `ghost_depth` u8 (≤ `MAX_GHOSTS`) · 23 `cost_unit` u8 ([`CostUnit`]) ·
/// 24 `guard_interventions` u32 · 25 `frozen_nav_holds` u32 · 26 `requests_busy` u32 ·
/// 27 `requests_unanswered` u32 · then the **mission progress block**:
/// 28 `mission_waypoint` u8 (the waypoint flown to, 0-based; = count once complete) ·
/// 29 `mission_waypoints` u8 (count, ≤ `MAX_WAYPOINTS`; 0: no mission) · 30 `mission_to_go_m`
/// f32 (m along the remaining waypoints, finite, ≥ 0) · 31..=36 the Ping360 port's six u32
/// counters of [`Ping360Counters`] in declaration order (all 0 where no Ping360 is driven) ·
/// 37 `rx_fec_corrected` u32 · 38 `rx_fec_uncorrectable` u32 (version 7) · 39 `current_x`
/// f32 · 40 `current_y` f32 (m/s over ground, finite; version 8).
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
    /// Cost of the last planner step, in `cost_unit`; 0 in a period held without a step.
    pub step_cost: u32,
    /// What `step_cost` counts.
    pub cost_unit: CostUnit,
    /// Counters since boot.
    pub counters: TelemetryCounters,
    /// How far along its mission the vehicle is (all zero: no mission).
    pub mission: MissionProgress,
    /// The Ping360 port's counters since boot (rows 31 ..= 36; zero without a Ping360).
    pub ping360: Ping360Counters,
    /// The current the firmware believes, m/s over ground (`crate::guidance::drift`; zero in
    /// still water or with the estimate off).
    pub current: Vec2,
}

impl TelemetryRepr {
    fn check(&self) -> Result<(), Error> {
        let m = &self.mission;
        if usize::from(m.count) > MAX_WAYPOINTS {
            return refuse(telemetry::MISSION_WAYPOINTS, Problem::OutOfRange);
        }
        if m.current > m.count {
            return refuse(telemetry::MISSION_WAYPOINT, Problem::OutOfRange);
        }
        within(telemetry::MISSION_TO_GO_M, m.to_go_m, 0.0, f32::MAX)?;
        finite(telemetry::CURRENT_X, self.current.x)?;
        finite(telemetry::CURRENT_Y, self.current.y)?;
        if usize::from(self.obstacles) > MAX_OBSTACLES {
            return refuse(telemetry::OBSTACLES, Problem::OutOfRange);
        }
        if usize::from(self.agents) > MAX_AGENTS {
            return refuse(telemetry::AGENTS, Problem::OutOfRange);
        }
        if usize::from(self.ghost_depth) > MAX_GHOSTS {
            return refuse(telemetry::GHOST_DEPTH, Problem::OutOfRange);
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
        let current = Vec2::new(r.f32()?, r.f32()?);
        r.finish()?;
        let t = TelemetryRepr {
            time_ms,
            mode: mode_from_codes(mode, reason, telemetry::MODE, telemetry::HOLD_REASON)?,
            obstacles,
            agents,
            ghost_depth,
            step_cost,
            cost_unit: CostUnit::from_code(unit)
                .ok_or(telemetry::COST_UNIT.error(Problem::UnknownCode))?,
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
            current,
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
        // Version 8: the current believed (rows 39, 40).
        w.f32(self.current.x)?;
        w.f32(self.current.y)?;
        Ok(w.len())
    }
}
