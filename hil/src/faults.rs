//! Link faults: byte corruption at a bit-error rate and dropped frames, applied to every frame
//! the harness sends, and the frame log, which records the traffic both ways.
//!
//! Navigation faults (delay, freeze, loss) and sonar dropouts act on what the runner sends, not
//! on bytes; they live in the runner.

use crate::firmware::Tap;
use crate::output::{Dir, FrameLog};

/// A small deterministic generator (xorshift64*), so a seed repeats a run's faults exactly.
#[derive(Clone, Debug)]
pub struct Rng(u64);

impl Rng {
    /// Seeded (0 is mapped to a fixed non-zero state).
    pub fn new(seed: u64) -> Self {
        Rng(if seed == 0 {
            0x9E37_79B9_7F4A_7C15
        } else {
            seed
        })
    }

    /// Uniform in [0, 1).
    pub fn unit(&mut self) -> f64 {
        let mut x = self.0;
        x ^= x >> 12;
        x ^= x << 25;
        x ^= x >> 27;
        self.0 = x;
        (x.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// What the fault tap did, for the summary and the tests.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct FaultCounts {
    /// Frames sent.
    pub frames: u64,
    /// Frames dropped.
    pub dropped: u64,
    /// Bits flipped.
    pub bits_flipped: u64,
    /// Frames with at least one flipped bit.
    pub corrupted: u64,
}

/// The tap between the runner and one firmware: faults out, log both ways.
pub struct FaultTap {
    bit_error_rate: f64,
    drop_rate: f64,
    rng: Rng,
    log: Option<FrameLog>,
    /// Simulation time stamped on the log, s.
    pub t: f64,
    /// What was done.
    pub counts: FaultCounts,
}

impl FaultTap {
    /// A tap with the given fault rates (0 for none), seeded, logging to `log`.
    pub fn new(bit_error_rate: f64, drop_rate: f64, seed: u64, log: Option<FrameLog>) -> Self {
        FaultTap {
            bit_error_rate: bit_error_rate.clamp(0.0, 1.0),
            drop_rate: drop_rate.clamp(0.0, 1.0),
            rng: Rng::new(seed),
            log,
            t: 0.0,
            counts: FaultCounts::default(),
        }
    }
}

impl FaultTap {
    /// The same log without the faults, for the scenario's set-up requests: a fault run tests
    /// the flight, not the set-up, and the frame log must still hold every byte the firmware
    /// was sent (`hil beliefs` replays it).
    pub fn clean(&mut self) -> CleanTap<'_> {
        CleanTap(self)
    }
}

/// [`FaultTap::clean`]: logs both ways, changes nothing.
pub struct CleanTap<'a>(&'a mut FaultTap);

impl Tap for CleanTap<'_> {
    fn outgoing(&mut self, frame: &[u8]) -> Option<Vec<u8>> {
        if let Some(log) = self.0.log.as_mut() {
            let _ = log.log(self.0.t, Dir::ToFirmware, frame);
        }
        Some(frame.to_vec())
    }

    fn incoming(&mut self, bytes: &[u8]) {
        self.0.incoming(bytes);
    }
}

impl Tap for FaultTap {
    fn outgoing(&mut self, frame: &[u8]) -> Option<Vec<u8>> {
        self.counts.frames += 1;
        if self.drop_rate > 0.0 && self.rng.unit() < self.drop_rate {
            self.counts.dropped += 1;
            return None;
        }
        let mut bytes = frame.to_vec();
        if self.bit_error_rate > 0.0 {
            let mut flipped = 0;
            for b in bytes.iter_mut() {
                for bit in 0..8 {
                    if self.rng.unit() < self.bit_error_rate {
                        *b ^= 1 << bit;
                        flipped += 1;
                    }
                }
            }
            if flipped > 0 {
                self.counts.corrupted += 1;
                self.counts.bits_flipped += flipped;
            }
        }
        if let Some(log) = self.log.as_mut() {
            let _ = log.log(self.t, Dir::ToFirmware, &bytes);
        }
        Some(bytes)
    }

    fn incoming(&mut self, bytes: &[u8]) {
        if let Some(log) = self.log.as_mut() {
            let _ = log.log(self.t, Dir::FromFirmware, bytes);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rates_are_what_they_say_and_repeat_with_the_seed() {
        let frame = vec![0x55u8; 100];
        let run = |seed| {
            let mut tap = FaultTap::new(1e-3, 0.1, seed, None);
            let sent: Vec<Option<Vec<u8>>> = (0..2000).map(|_| tap.outgoing(&frame)).collect();
            (sent, tap.counts)
        };
        let (a, counts) = run(7);
        let (b, _) = run(7);
        assert_eq!(a, b);
        // 10 % dropped, ±3 %; 800 bits a frame at 10⁻³: about 0.8 flips a frame.
        assert!((150..=250).contains(&counts.dropped), "{counts:?}");
        let kept = counts.frames - counts.dropped;
        let per_frame = counts.bits_flipped as f64 / kept as f64;
        assert!((0.6..1.0).contains(&per_frame), "{per_frame}");
    }

    #[test]
    fn the_clean_tap_logs_what_it_sends_and_spares_it_the_faults() {
        let dir = std::env::temp_dir().join(format!("vpf-clean-tap-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let log = FrameLog::create(&dir, "v0").unwrap();
        let path = dir.join("frames_v0.log");
        // Every frame dropped, every bit flipped: the faulty side sends nothing.
        let mut tap = FaultTap::new(1.0, 1.0, 3, Some(log));
        assert_eq!(tap.outgoing(&[9]), None);
        tap.t = 1.5;
        assert_eq!(tap.clean().outgoing(&[1, 2, 3]), Some(vec![1, 2, 3]));
        assert_eq!(tap.counts.frames, 1, "the clean frame is not a faulted one");
        drop(tap);
        let frames = FrameLog::replay(&path).unwrap();
        assert_eq!(frames, vec![(1.5, Dir::ToFirmware, vec![1, 2, 3])]);
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn no_faults_no_change() {
        let mut tap = FaultTap::new(0.0, 0.0, 1, None);
        assert_eq!(tap.outgoing(&[1, 2, 3]), Some(vec![1, 2, 3]));
    }
}
