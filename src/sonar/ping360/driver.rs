//! The Ping360 driver: steps the head with `transducer` commands and turns each `device_data`
//! into a [`Scanline`] for the feature extractor and the evidence map.
//!
//! Hardware-independent: bytes from the sonar go into [`Ping360::on_bytes`], bytes for it
//! leave through a caller-supplied transmit function (`FnMut(&[u8]) -> bool`, `false` when it
//! cannot take the frame), and [`Ping360::poll`] is called periodically for the timeouts. Both
//! run in the background context (nothing here waits); time is an argument.
//!
//! **The cycle.** One command is outstanding at a time: `transducer` at the current angle;
//! its `device_data` (checksum matched, head accepted) becomes a scanline and the next command
//! goes out at once, one step on (continuously round, or back and forth over the sector). An
//! answer dropped for its checksum (counted there) also steps on at once: the sonar is idle
//! again. No answer within `timeout_ms` (or a `nack` of the command): counted as a timeout,
//! the head steps on and the next command goes out. A `device_data` for another angle (a late answer)
//! still becomes a scanline; the command outstanding stays outstanding.
//!
//! **The scanline** of a `device_data`: time and vehicle pose are those when its head arrived
//! (the ping was a listening window and a few milliseconds of motor earlier: the sonar sends
//! the data after the echo is in); bearing from the angle through the mounting
//! ([`Ping360Config::bearing_rad`]); one bin per `k` samples ([`super::pool`]); range
//! `bins × k × sample_period × 25 ns × c / 2`, with the `device_data`'s own sample period.
//!
//! **Counters** ([`Ping360Counters`]): pings turned into scanlines, commands sent, timeouts,
//! and the stream decoder's checksum errors, malformed frames and skipped bytes. Nothing is
//! fatal.

use crate::link::ping::ping360::DeviceDataHead;
use crate::link::ping::{
    emit_frame, id, Decoder, Event, Message, NackRepr, PingSettings, TransducerRepr, HOST_ID,
};
use crate::sonar::{Pose, Scanline};

use super::config::{ConfigError, Ping360Config};
use super::pool::Pool;
use crate::link::ping::ping360::GRADIANS;

/// Device id the commands are addressed to (the Ping360 answers any; Blue Robotics' tools
/// send 0, "unknown").
pub const SONAR_ID: u8 = 0;
/// Length of a `transducer` frame on the wire.
pub const TRANSDUCER_FRAME_LEN: usize = 8 + crate::link::ping::ping360::TRANSDUCER_LEN + 2;

// Its RAM on the target, checked when the library is built for it (`cargo clippy-fw`).
#[cfg(target_os = "none")]
const _: () = assert!(core::mem::size_of::<Ping360>() <= 512);

pub use crate::link::counters::Ping360Counters;

/// The `device_data` being received.
#[derive(Clone, Copy, Debug)]
struct Incoming {
    settings: PingSettings,
    data_len: u16,
    time_ms: u64,
    pose: Option<Pose>,
}

/// The command outstanding.
#[derive(Clone, Copy, Debug)]
struct Pending {
    angle: u16,
    sent_ms: u64,
}

/// The Ping360 driver. About 0.5 KiB, no heap (`size_of` is reported by its tests).
#[derive(Clone, Debug)]
pub struct Ping360 {
    cfg: Ping360Config,
    decoder: Decoder,
    pool: Pool,
    incoming: Option<Incoming>,
    pending: Option<Pending>,
    /// Angle of the next (or outstanding) command, and the sector offset it is at.
    angle: u16,
    offset: u16,
    /// +1 or −1: where the head goes next in a sector.
    forward: bool,
    data: u32,
    commands: u32,
    timeouts: u32,
}

impl Ping360 {
    /// A driver with a checked configuration. Nothing is sent until the first
    /// [`Ping360::poll`].
    pub fn new(cfg: Ping360Config) -> Result<Self, ConfigError> {
        cfg.validate()?;
        Ok(Ping360 {
            cfg,
            decoder: Decoder::new(),
            pool: Pool::new(),
            incoming: None,
            pending: None,
            angle: cfg.start_grad,
            offset: 0,
            forward: true,
            data: 0,
            commands: 0,
            timeouts: 0,
        })
    }

    /// Its configuration.
    pub fn config(&self) -> &Ping360Config {
        &self.cfg
    }

    /// What it has done so far.
    pub fn counters(&self) -> Ping360Counters {
        let d = self.decoder.counters();
        Ping360Counters {
            data: self.data,
            commands: self.commands,
            timeouts: self.timeouts,
            checksum_errors: d.checksum,
            malformed: d.oversize.saturating_add(d.malformed),
            bytes_skipped: d.skipped,
        }
    }

    /// The head angle of the next (or outstanding) command, gradians.
    pub fn angle(&self) -> u16 {
        self.angle
    }

    /// Call periodically: sends the first command, and steps on past a command unanswered for
    /// `timeout_ms` (counted).
    pub fn poll(&mut self, now_ms: u64, tx: &mut impl FnMut(&[u8]) -> bool) {
        match self.pending {
            None => self.send(now_ms, tx),
            Some(p) if now_ms.saturating_sub(p.sent_ms) >= u64::from(self.cfg.timeout_ms) => {
                self.timeouts = self.timeouts.saturating_add(1);
                self.step();
                self.send(now_ms, tx);
            }
            Some(_) => {}
        }
    }

    /// Feeds bytes received from the sonar at time `now_ms`, when the vehicle's newest pose
    /// was `pose`. Each complete ping is handed to `out` with the pose latched when its head
    /// arrived; the next command goes out through `tx`.
    pub fn on_bytes(
        &mut self,
        bytes: &[u8],
        now_ms: u64,
        pose: Option<Pose>,
        tx: &mut impl FnMut(&[u8]) -> bool,
        out: &mut impl FnMut(&Scanline<'_>, Option<Pose>),
    ) {
        let mut rest = bytes;
        while !rest.is_empty() {
            let (n, ev) = self.decoder.feed(rest);
            let (used, tail) = rest.split_at_checked(n).unwrap_or((rest, &[]));
            rest = tail;
            match ev {
                Event::DataHead(_, head) => self.start(head, now_ms, pose),
                Event::Data(k) => {
                    if self.incoming.is_some() {
                        self.pool
                            .push(used.get(n.saturating_sub(k)..).unwrap_or(&[]));
                    }
                }
                Event::DataEnd(_) => {
                    if let Some(inc) = self.incoming.take() {
                        self.finish(inc, now_ms, tx, out);
                    }
                }
                // Counted by the decoder; whatever was pooled is thrown away. If it was the
                // answer to the command outstanding, the sonar is idle again: step on now
                // rather than wait out the timeout.
                Event::Dropped(_) => {
                    let lost = self.incoming.take();
                    if lost
                        .is_some_and(|i| self.pending.is_some_and(|p| p.angle == i.settings.angle))
                    {
                        self.step();
                        self.send(now_ms, tx);
                    }
                }
                Event::Frame(h) if h.message_id == id::NACK => {
                    let nacked = self
                        .decoder
                        .payload()
                        .and_then(|p| NackRepr::parse(p).ok())
                        .map(|n| n.nacked_id);
                    if nacked == Some(id::TRANSDUCER) && self.pending.is_some() {
                        self.timeouts = self.timeouts.saturating_add(1);
                        self.step();
                        self.send(now_ms, tx);
                    }
                }
                // Acks, versions and anything else: nothing to do.
                Event::Frame(_) | Event::Nothing => {}
            }
        }
    }

    fn start(&mut self, head: DeviceDataHead, now_ms: u64, pose: Option<Pose>) {
        self.pool.start(head.data_len);
        self.incoming = Some(Incoming {
            settings: head.settings,
            data_len: head.data_len,
            time_ms: now_ms,
            pose,
        });
    }

    /// A `device_data` whose checksum matched.
    fn finish(
        &mut self,
        inc: Incoming,
        now_ms: u64,
        tx: &mut impl FnMut(&[u8]) -> bool,
        out: &mut impl FnMut(&Scanline<'_>, Option<Pose>),
    ) {
        let s = inc.settings;
        if let (Some(bins), true) = (self.pool.bins(), inc.data_len > 0) {
            let per_bin = f32::from(self.pool.factor()) * s.sample_m(self.cfg.sound_speed);
            let scan = Scanline {
                time_ms: inc.time_ms,
                bearing_rad: self.cfg.bearing_rad(s.angle),
                step_rad: self.cfg.step_rad(),
                range_m: bins.len() as f32 * per_bin,
                bins,
            };
            self.data = self.data.saturating_add(1);
            out(&scan, inc.pose);
        }
        if self.pending.is_some_and(|p| p.angle == s.angle) {
            self.step();
            self.send(now_ms, tx);
        }
    }

    /// Sends the command for the current angle; on a full transmit queue nothing is
    /// outstanding and the next poll tries again.
    fn send(&mut self, now_ms: u64, tx: &mut impl FnMut(&[u8]) -> bool) {
        let m = Message::Transducer(TransducerRepr {
            settings: self.cfg.settings(self.angle),
            transmit: true,
        });
        let mut buf = [0u8; TRANSDUCER_FRAME_LEN];
        // A validated configuration always emits; should it not, nothing is sent.
        let sent = emit_frame(&m, HOST_ID, SONAR_ID, &mut buf)
            .ok()
            .and_then(|n| buf.get(..n))
            .is_some_and(tx);
        self.pending = sent.then_some(Pending {
            angle: self.angle,
            sent_ms: now_ms,
        });
        if sent {
            self.commands = self.commands.saturating_add(1);
        }
    }

    /// Moves the head one step: round the circle, or back and forth over the sector (turning
    /// at the first step that would pass an end).
    fn step(&mut self) {
        let (step, width) = (self.cfg.step_grad, self.cfg.width_grad);
        if width >= GRADIANS {
            self.angle = (self.angle + step) % GRADIANS;
            return;
        }
        let next = if self.forward {
            self.offset.checked_add(step).filter(|o| *o <= width)
        } else {
            self.offset.checked_sub(step)
        };
        self.offset = match next {
            Some(o) => o,
            None => {
                self.forward = !self.forward;
                if self.forward {
                    self.offset.saturating_add(step).min(width)
                } else {
                    self.offset.saturating_sub(step)
                }
            }
        };
        self.angle = (self.cfg.start_grad + self.offset) % GRADIANS;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::link::ping::{DeviceDataRepr, Frame};
    use crate::math::Vec2;
    extern crate std;
    use std::vec::Vec;

    /// A sonar that answers each command with `device_data` of `n` samples, the sample at
    /// index `echo` 200 and the rest 10.
    fn answer(cmd: &[u8], n: usize, echo: usize) -> Vec<u8> {
        let f = Frame::new_checked(cmd).unwrap();
        let Ok(Message::Transducer(t)) = f.message() else {
            panic!("not a transducer: {cmd:?}")
        };
        let mut data = std::vec![10u8; n];
        data[echo] = 200;
        let s = PingSettings {
            number_of_samples: n as u16,
            mode: 0,
            ..t.settings
        };
        let m = Message::DeviceData(DeviceDataRepr {
            settings: s,
            data: &data,
        });
        let mut buf = std::vec![0u8; 2000];
        let len = emit_frame(&m, 2, 0, &mut buf).unwrap();
        buf.truncate(len);
        buf
    }

    fn pose() -> Pose {
        Pose {
            position: Vec2::new(1.0, 2.0),
            heading: 0.5,
        }
    }

    #[test]
    fn it_steps_round_turning_each_answer_into_a_scanline() {
        let cfg = Ping360Config::default();
        let mut d = Ping360::new(cfg).unwrap();
        let mut sent: Vec<Vec<u8>> = Vec::new();
        d.poll(0, &mut |f| {
            sent.push(f.to_vec());
            true
        });
        assert_eq!(sent.len(), 1);
        let mut scans = Vec::new();
        for i in 0..250u64 {
            let reply = answer(sent.last().unwrap(), 600, 300);
            // Fed in two pieces, as a UART would deliver it.
            let (a, b) = reply.split_at(100);
            for (k, piece) in [a, b].into_iter().enumerate() {
                d.on_bytes(
                    piece,
                    100 * i + k as u64,
                    Some(pose()),
                    &mut |f| {
                        sent.push(f.to_vec());
                        true
                    },
                    &mut |s, p| {
                        scans.push((s.time_ms, s.bearing_rad, s.range_m, s.bins.to_vec(), p))
                    },
                );
            }
        }
        assert_eq!(scans.len(), 250);
        assert_eq!(sent.len(), 251);
        let c = d.counters();
        assert_eq!((c.data, c.commands, c.timeouts), (250, 251, 0));
        assert_eq!((c.checksum_errors, c.malformed, c.bytes_skipped), (0, 0, 0));
        // Angles 0, 2, 4, ... wrapping at 400; time and pose from the head's arrival.
        let (t0, b0, r0, bins0, p0) = &scans[0];
        assert_eq!(*t0, 0);
        assert!((b0 - cfg.bearing_rad(0)).abs() < 1e-6);
        assert!((r0 - 30.0).abs() < 0.01, "{r0}");
        assert_eq!(bins0.len(), 300);
        // Sample 300 of 600 is in bin 150: (10 + 200) / 2 rounded.
        assert_eq!(bins0[150], 105);
        assert_eq!(*p0, Some(pose()));
        assert!((scans[201].1 - cfg.bearing_rad(2)).abs() < 1e-6);
    }

    #[test]
    fn a_sector_goes_back_and_forth() {
        let cfg = Ping360Config {
            start_grad: 390,
            width_grad: 20,
            step_grad: 5,
            ..Ping360Config::default()
        };
        let mut d = Ping360::new(cfg).unwrap();
        let mut angles = Vec::new();
        for _ in 0..12 {
            angles.push(d.angle());
            d.step();
        }
        assert_eq!(angles, [390, 395, 0, 5, 10, 5, 0, 395, 390, 395, 0, 5]);
    }

    #[test]
    fn timeouts_nacks_and_corruption_are_counted_and_never_stop_it() {
        let cfg = Ping360Config::default();
        let mut d = Ping360::new(cfg).unwrap();
        let sent: std::cell::RefCell<Vec<Vec<u8>>> = Default::default();
        let mut tx = |f: &[u8]| {
            sent.borrow_mut().push(f.to_vec());
            true
        };
        d.poll(0, &mut tx);
        d.poll(499, &mut tx);
        assert_eq!(d.counters().timeouts, 0);
        d.poll(500, &mut tx);
        assert_eq!(d.counters().timeouts, 1);
        assert_eq!(d.angle(), 2);
        // A nack of the command: the same.
        let nack = Message::Nack(NackRepr {
            nacked_id: id::TRANSDUCER,
            text: b"busy",
        });
        let mut buf = [0u8; 32];
        let n = emit_frame(&nack, 2, 0, &mut buf).unwrap();
        let mut scans = 0;
        d.on_bytes(&buf[..n], 1100, None, &mut tx, &mut |_, _| scans += 1);
        assert_eq!((d.counters().timeouts, d.angle()), (2, 4));
        // A corrupted answer: dropped, counted, no scanline; noise: skipped.
        let mut bad = answer(&sent.borrow().last().unwrap().clone(), 300, 10);
        bad[50] ^= 4;
        d.on_bytes(&bad, 1200, None, &mut tx, &mut |_, _| scans += 1);
        d.on_bytes(b"\x00\x01xyz", 1200, None, &mut tx, &mut |_, _| scans += 1);
        let c = d.counters();
        assert_eq!((c.checksum_errors, c.bytes_skipped, scans), (1, 5, 0));
        // The corrupted answer was to the command outstanding: the head stepped on at once.
        assert_eq!((d.angle(), c.timeouts), (6, 2));
        // Then a good answer goes through.
        let good = answer(&sent.borrow().last().unwrap().clone(), 300, 10);
        d.on_bytes(&good, 1300, None, &mut tx, &mut |_, p| {
            assert_eq!(p, None);
            scans += 1
        });
        assert_eq!(scans, 1);
        assert_eq!(d.angle(), 8);
    }

    #[test]
    fn a_full_transmit_queue_retries_at_the_next_poll() {
        let mut d = Ping360::new(Ping360Config::default()).unwrap();
        d.poll(0, &mut |_| false);
        assert_eq!(d.counters().commands, 0);
        let mut n = 0;
        d.poll(10, &mut |_| {
            n += 1;
            true
        });
        assert_eq!((n, d.counters().commands), (1, 1));
    }

    #[test]
    fn its_ram_is_small() {
        // On the host (64-bit) it is a little larger than on the Cortex-M4 (32-bit pointers).
        let size = core::mem::size_of::<Ping360>();
        std::println!("Ping360 driver: {size} bytes");
        assert!(size <= 560, "{size}");
    }
}
