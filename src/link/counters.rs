//! The counters `Telemetry` reports: the firmware's ([`TelemetryCounters`]) and the Ping360
//! driver's ([`Ping360Counters`]), each a saturating u32 since boot, in wire order.

use super::decoder::RxCounters;
#[cfg(doc)]
use super::ReplyStatus;

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
    /// Sonar features extracted (glimpses included: [`crate::sonar::GLIMPSE_INTENSITY`]).
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

/// The Ping360 driver's counters (`crate::sonar::ping360`), for telemetry. Saturating.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct Ping360Counters {
    /// `device_data` turned into scanlines.
    pub data: u32,
    /// `transducer` commands sent.
    pub commands: u32,
    /// Commands not answered within the timeout (or refused with a `nack`).
    pub timeouts: u32,
    /// Frames dropped for a checksum mismatch.
    pub checksum_errors: u32,
    /// Frames refused otherwise: a header announcing an oversize payload, a `device_data`
    /// whose data length or fields are wrong.
    pub malformed: u32,
    /// Bytes skipped looking for a frame start.
    pub bytes_skipped: u32,
}

impl Ping360Counters {
    /// Number of counters (telemetry rows).
    pub const COUNT: usize = 6;

    /// The counters in telemetry's order.
    pub const fn to_array(&self) -> [u32; Self::COUNT] {
        [
            self.data,
            self.commands,
            self.timeouts,
            self.checksum_errors,
            self.malformed,
            self.bytes_skipped,
        ]
    }

    /// The counters from telemetry's order.
    pub const fn from_array(a: [u32; Self::COUNT]) -> Self {
        let [data, commands, timeouts, checksum_errors, malformed, bytes_skipped] = a;
        Ping360Counters {
            data,
            commands,
            timeouts,
            checksum_errors,
            malformed,
            bytes_skipped,
        }
    }
}
