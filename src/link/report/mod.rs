//! Reports, firmware → host: `Command`, `Telemetry`, `Reply` and `Log`, one file each; their
//! rows are named in [`field`]. The mode codes they carry are [`modes`](super::modes), the
//! counters [`counters`](super::counters).

mod command;
mod log;
mod reply;
mod telemetry;

pub use command::{CommandRepr, COMMAND_LEN};
pub use log::{LogLevel, LogRepr};
pub use reply::{ReplyRepr, ReplyStatus, FIELD_WHOLE_MESSAGE};
pub use telemetry::{
    CostUnit, TelemetryRepr, TELEMETRY_LEN, TELEMETRY_MISSION_ROW, TELEMETRY_PING360_ROW,
};

/// Each message's rows (docs/protocol.md §6), by name: each constant is the row of the field
/// it names.
#[allow(missing_docs)]
pub mod field {
    /// `Command`.
    pub mod command {
        use crate::link::layout::Field;

        pub const TIME_MS: Field = Field::new(0, 0, "u64", "time_ms");
        pub const PSI_SET: Field = Field::new(1, 8, "f32", "psi_set");
        pub const V_SET: Field = Field::new(2, 12, "f32", "v_set");
        pub const A_C: Field = Field::new(3, 16, "f32", "a_c");
        pub const V_C: Field = Field::new(4, 20, "f32", "v_c");
        pub const I_SURGE: Field = Field::new(5, 24, "f32", "i_surge");
        pub const ALPHA_C: Field = Field::new(6, 28, "f32", "alpha_c");
        pub const OMEGA_C: Field = Field::new(7, 32, "f32", "omega_c");
        pub const PHI_C: Field = Field::new(8, 36, "f32", "phi_c");
        pub const TARGET_X: Field = Field::new(9, 40, "f32", "target_x");
        pub const TARGET_Y: Field = Field::new(10, 44, "f32", "target_y");
        pub const CLEARANCE_M: Field = Field::new(11, 48, "f32", "clearance_m");
        pub const FORCE_X: Field = Field::new(12, 52, "f32", "force_x");
        pub const FORCE_Y: Field = Field::new(13, 56, "f32", "force_y");
        pub const VELOCITY_X: Field = Field::new(14, 60, "f32", "velocity_x");
        pub const VELOCITY_Y: Field = Field::new(15, 64, "f32", "velocity_y");
        pub const MODE: Field = Field::new(16, 68, "u8", "mode");
        pub const HOLD_REASON: Field = Field::new(17, 69, "u8", "hold_reason");
        pub const GHOST_DEPTH: Field = Field::new(18, 70, "u8", "ghost_depth");
        /// Every row, in order.
        pub const ALL: &[Field] = &[
            TIME_MS,
            PSI_SET,
            V_SET,
            A_C,
            V_C,
            I_SURGE,
            ALPHA_C,
            OMEGA_C,
            PHI_C,
            TARGET_X,
            TARGET_Y,
            CLEARANCE_M,
            FORCE_X,
            FORCE_Y,
            VELOCITY_X,
            VELOCITY_Y,
            MODE,
            HOLD_REASON,
            GHOST_DEPTH,
        ];
    }

    /// `Telemetry`.
    pub mod telemetry {
        use crate::link::layout::Field;

        pub const TIME_MS: Field = Field::new(0, 0, "u64", "time_ms");
        pub const STEP_COST: Field = Field::new(1, 8, "u32", "step_cost");
        pub const RX_FRAMES: Field = Field::new(2, 12, "u32", "rx_frames");
        pub const RX_CRC_ERRORS: Field = Field::new(3, 16, "u32", "rx_crc_errors");
        pub const RX_OVERSIZE: Field = Field::new(4, 20, "u32", "rx_oversize");
        pub const RX_FRAMING_ERRORS: Field = Field::new(5, 24, "u32", "rx_framing_errors");
        pub const RX_UNKNOWN: Field = Field::new(6, 28, "u32", "rx_unknown");
        pub const RX_BAD_PAYLOAD: Field = Field::new(7, 32, "u32", "rx_bad_payload");
        pub const BAD_NAV: Field = Field::new(8, 36, "u32", "bad_nav");
        pub const BAD_PARAMS: Field = Field::new(9, 40, "u32", "bad_params");
        pub const BAD_MISSION: Field = Field::new(10, 44, "u32", "bad_mission");
        pub const RX_BYTES_DROPPED: Field = Field::new(11, 48, "u32", "rx_bytes_dropped");
        pub const FEATURES_DROPPED: Field = Field::new(12, 52, "u32", "features_dropped");
        pub const TX_FRAMES_DROPPED: Field = Field::new(13, 56, "u32", "tx_frames_dropped");
        pub const DEADLINE_OVERRUNS: Field = Field::new(14, 60, "u32", "deadline_overruns");
        pub const TABLE_FULL: Field = Field::new(15, 64, "u32", "table_full");
        pub const TABLE_EVICTED: Field = Field::new(16, 68, "u32", "table_evicted");
        pub const FEATURES_EXTRACTED: Field = Field::new(17, 72, "u32", "features_extracted");
        pub const MODE: Field = Field::new(18, 76, "u8", "mode");
        pub const HOLD_REASON: Field = Field::new(19, 77, "u8", "hold_reason");
        pub const OBSTACLES: Field = Field::new(20, 78, "u8", "obstacles");
        pub const AGENTS: Field = Field::new(21, 79, "u8", "agents");
        pub const GHOST_DEPTH: Field = Field::new(22, 80, "u8", "ghost_depth");
        pub const COST_UNIT: Field = Field::new(23, 81, "u8", "cost_unit");
        pub const GUARD_INTERVENTIONS: Field = Field::new(24, 82, "u32", "guard_interventions");
        pub const FROZEN_NAV_HOLDS: Field = Field::new(25, 86, "u32", "frozen_nav_holds");
        pub const REQUESTS_BUSY: Field = Field::new(26, 90, "u32", "requests_busy");
        pub const REQUESTS_UNANSWERED: Field = Field::new(27, 94, "u32", "requests_unanswered");
        pub const MISSION_WAYPOINT: Field = Field::new(28, 98, "u8", "mission_waypoint");
        pub const MISSION_WAYPOINTS: Field = Field::new(29, 99, "u8", "mission_waypoints");
        pub const MISSION_TO_GO_M: Field = Field::new(30, 100, "f32", "mission_to_go_m");
        pub const PING360_DATA: Field = Field::new(31, 104, "u32", "ping360_data");
        pub const PING360_COMMANDS: Field = Field::new(32, 108, "u32", "ping360_commands");
        pub const PING360_TIMEOUTS: Field = Field::new(33, 112, "u32", "ping360_timeouts");
        pub const PING360_CHECKSUM_ERRORS: Field =
            Field::new(34, 116, "u32", "ping360_checksum_errors");
        pub const PING360_MALFORMED: Field = Field::new(35, 120, "u32", "ping360_malformed");
        pub const PING360_BYTES_SKIPPED: Field =
            Field::new(36, 124, "u32", "ping360_bytes_skipped");
        pub const RX_FEC_CORRECTED: Field = Field::new(37, 128, "u32", "rx_fec_corrected");
        pub const RX_FEC_UNCORRECTABLE: Field = Field::new(38, 132, "u32", "rx_fec_uncorrectable");
        pub const CURRENT_X: Field = Field::new(39, 136, "f32", "current_x");
        pub const CURRENT_Y: Field = Field::new(40, 140, "f32", "current_y");
        /// Every row, in order.
        pub const ALL: &[Field] = &[
            TIME_MS,
            STEP_COST,
            RX_FRAMES,
            RX_CRC_ERRORS,
            RX_OVERSIZE,
            RX_FRAMING_ERRORS,
            RX_UNKNOWN,
            RX_BAD_PAYLOAD,
            BAD_NAV,
            BAD_PARAMS,
            BAD_MISSION,
            RX_BYTES_DROPPED,
            FEATURES_DROPPED,
            TX_FRAMES_DROPPED,
            DEADLINE_OVERRUNS,
            TABLE_FULL,
            TABLE_EVICTED,
            FEATURES_EXTRACTED,
            MODE,
            HOLD_REASON,
            OBSTACLES,
            AGENTS,
            GHOST_DEPTH,
            COST_UNIT,
            GUARD_INTERVENTIONS,
            FROZEN_NAV_HOLDS,
            REQUESTS_BUSY,
            REQUESTS_UNANSWERED,
            MISSION_WAYPOINT,
            MISSION_WAYPOINTS,
            MISSION_TO_GO_M,
            PING360_DATA,
            PING360_COMMANDS,
            PING360_TIMEOUTS,
            PING360_CHECKSUM_ERRORS,
            PING360_MALFORMED,
            PING360_BYTES_SKIPPED,
            RX_FEC_CORRECTED,
            RX_FEC_UNCORRECTABLE,
            CURRENT_X,
            CURRENT_Y,
        ];
    }

    /// `Reply`.
    pub mod reply {
        use crate::link::layout::Field;

        pub const TO_TYPE: Field = Field::new(0, 0, "u8", "to_type");
        pub const TO_SEQ: Field = Field::new(1, 1, "u16", "to_seq");
        pub const STATUS: Field = Field::new(2, 3, "u8", "status");
        pub const FIELD: Field = Field::new(3, 4, "u8", "field");
        pub const PROBLEM: Field = Field::new(4, 5, "u8", "problem");
        /// Every row, in order.
        pub const ALL: &[Field] = &[TO_TYPE, TO_SEQ, STATUS, FIELD, PROBLEM];
    }

    /// `Log`.
    pub mod log {
        use crate::link::layout::Field;

        pub const LEVEL: Field = Field::new(0, 0, "u8", "level");
        pub const TEXT: Field = Field::new(1, 1, "n × u8", "text");
        /// Every row, in order.
        pub const ALL: &[Field] = &[LEVEL, TEXT];
    }
}

#[cfg(test)]
pub(crate) mod tests {
    extern crate std;
    use super::*;
    use crate::link::counters::{Ping360Counters, TelemetryCounters};
    use crate::link::decoder::RxCounters;
    use crate::link::frame::{Header, MessageType};
    use crate::link::payload::Payload;
    use crate::link::{Error, Problem, MAX_LOG_LEN};
    use crate::math::Vec2;
    use crate::params::ParamError;
    use crate::params::{ParamProblem, MAX_GHOSTS};
    use crate::types::HoldReason;
    use crate::types::{Command, FormationError, MissionProgress, Mode, PidSetpoints, StepError};
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
            current: Vec2::new(0.25, -0.125),
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
        // Rows 39, 40: the current believed, (0.25, −0.125) m/s.
        want.extend([0x00, 0x00, 0x80, 0x3e, 0x00, 0x00, 0x00, 0xbe]);
        assert_eq!(want.len(), TELEMETRY_LEN);
        assert_eq!(TELEMETRY_LEN, 144);
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
            (-3.0f32..3.0, -3.0f32..3.0),
        )
            .prop_map(
                |(t, mode, (o, a, g), cost, unit, c, (i, n, d), p, (cx, cy))| TelemetryRepr {
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
                    current: Vec2::new(cx, cy),
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

    /// OwnedMessage log fields: (level code, text of at most MAX_LOG_LEN bytes).
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
            let mut out = [0u8; TELEMETRY_LEN];
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
        fn report_parsers_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..160)) {
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
