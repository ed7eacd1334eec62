//! `Command` (0x81): one planner period's output.

use super::field::command;
use crate::link::codec::{angle, finite, refuse, within, Reader, Writer};
use crate::link::frame::MessageType;
use crate::link::modes::{mode_codes, mode_from_codes};
use crate::link::payload::Payload;
use crate::link::{Error, Problem};
use crate::params::MAX_GHOSTS;
use crate::types::{Command, PidSetpoints, MAX_NAV_SPEED};

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
        angle(command::PSI_SET, c.psi_set)?;
        within(command::V_SET, c.v_set, 0.0, MAX_NAV_SPEED)?;
        finite(command::A_C, s.a_c)?;
        finite(command::V_C, s.v_c)?;
        finite(command::I_SURGE, s.i_surge)?;
        finite(command::ALPHA_C, s.alpha_c)?;
        finite(command::OMEGA_C, s.omega_c)?;
        angle(command::PHI_C, s.phi_c)?;
        finite(command::TARGET_X, c.target.x)?;
        finite(command::TARGET_Y, c.target.y)?;
        // +∞ is a valid clearance: nothing in the world.
        if c.clearance_m.is_nan() || c.clearance_m == f32::NEG_INFINITY {
            return refuse(command::CLEARANCE_M, Problem::NonFinite);
        }
        finite(command::FORCE_X, c.force.x)?;
        finite(command::FORCE_Y, c.force.y)?;
        finite(command::VELOCITY_X, c.velocity.x)?;
        finite(command::VELOCITY_Y, c.velocity.y)?;
        if usize::from(c.ghost_depth) > MAX_GHOSTS {
            return refuse(command::GHOST_DEPTH, Problem::OutOfRange);
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
                mode: mode_from_codes(mode, reason, command::MODE, command::HOLD_REASON)?,
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
