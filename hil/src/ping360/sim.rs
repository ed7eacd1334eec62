//! A simulated Blue Robotics Ping360 on its own pty: it answers the firmware's `transducer`
//! commands with `device_data` rendered by the same ray-cast sonar model as the Micron-like
//! scanlines (`crate::sim::sonar`), along the bearing the commanded angle has on the vehicle.
//!
//! **Timing.** A command sent at time `t₀` pings at `t₀ + overhead` (the head's step, the
//! sonar model's `ping_overhead_s`), listens `2R/c`, and its `device_data` has arrived once its
//! bytes have crossed a 115 200-baud line (10 bits a byte): at 30 m over 300 samples that is
//! 5 + 40 + 28 ms = 73 ms a ping, a full circle of 200 two-gradian steps in 14.6 s. The
//! firmware sends the next command as soon as the data is in, at the data's arrival time.
//!
//! **Lockstep stays deterministic** across the two ports, though the firmware reads them in
//! two threads: the harness is the only one that moves, and it waits for the firmware's answer
//! at each step. Per period, before navigation and the `Tick` go out on the main link: (1) it
//! reads every command the firmware has sent, as many as the last `Telemetry` counted
//! (`ping360_commands`, row 29: commands go out before the period's `Command`); (2) it answers
//! the command due by now, and, when those bytes make the firmware send its next command at
//! once, waits for that command. Whether they do is known here: a mirror of the firmware's own
//! driver (`vpf::sonar::ping360::Ping360`, same settings) is fed the very bytes written (after
//! the fault tap) and the same periods, so it sends exactly when the firmware's does — after
//! an answer it accepts, and after one whose head it took but whose checksum failed; not after
//! one corrupted beyond recognition (that one times out at a period, counted in telemetry).
//!
//! The raw bytes sent (as the firmware received them) can be logged: `ping360_NAME.bin` in a
//! run's output, which `hil sonar-replay --ping360` reads.

use std::fs::File;
use std::io::{BufWriter, Read, Write};
use std::path::Path;
use std::time::{Duration, Instant};

use vpf::link::ping::{emit_frame, Decoder, DeviceDataRepr, Event, Message, TransducerRepr};
use vpf::sonar::ping360::{Ping360, Ping360Config};

use crate::firmware::Tap;
use crate::scenario::Sonar as SonarSpec;
use crate::sim::sonar::Sonar;
use crate::types::{SimObstacle, VehicleState, P2};

/// Speed of sound of the simulated water, m/s (the firmware's default).
pub const SOUND_SPEED: f64 = 1500.0;
/// The simulated serial line's baud rate.
pub const BAUD: f64 = 115_200.0;
/// Longest wait for the firmware's next command once it has data it accepts (or for the
/// commands its last telemetry counted): far past any host-process answer; past it the run
/// stops with an error rather than hang.
pub const ANSWER_WAIT: Duration = Duration::from_secs(10);
/// Largest raw log per vehicle, bytes; past it logging stops (the run goes on).
pub const MAX_RAW_LOG_BYTES: u64 = 256 << 20;

/// The firmware's Ping360 settings for a scenario's `[sonar]` (samples from `bins`, the step
/// from `step_deg`, the range from `range_m`), or the offending key and why.
pub fn firmware_config(s: &SonarSpec) -> Result<Ping360Config, (&'static str, String)> {
    let grad = s.step.to_degrees() / 0.9;
    let step = grad.round();
    if (grad - step).abs() > 1e-6 || !(1.0..=12.0).contains(&step) {
        return Err((
            "step_deg",
            format!(
                "a Ping360 steps in whole gradians of 0.9°, 1 ..= 12; got {:.4}°",
                s.step.to_degrees()
            ),
        ));
    }
    if !(200..=1200).contains(&s.bins) {
        return Err((
            "bins",
            format!("a Ping360 takes 200 ..= 1200 samples; got {}", s.bins),
        ));
    }
    let range = s.range_m as f32;
    let period = Ping360Config::sample_period_for(range, s.bins, SOUND_SPEED as f32).ok_or((
        "range_m",
        format!(
            "no Ping360 sample period (80 ..= 40000 × 25 ns) reaches {} m over {} samples",
            s.range_m, s.bins
        ),
    ))?;
    let mut cfg = Ping360Config {
        step_grad: step as u16,
        samples: s.bins,
        sample_period: period,
        sound_speed: SOUND_SPEED as f32,
        ..Ping360Config::default()
    };
    // A lost answer costs the timeout: four pings' time (at least 100 ms), not a second, so a
    // lossy port slows the sweep by little (the simulated head answers in one ping's time).
    let ping_s = 0.005 + 2.0 * s.range_m / SOUND_SPEED + (24.0 + f64::from(s.bins)) * 10.0 / BAUD;
    cfg.timeout_ms = ((4.0 * ping_s * 1000.0).ceil() as u32).clamp(100, 10_000);
    cfg.validate()
        .map_err(|e| ("range_m", format!("refused by the firmware's driver: {e}")))?;
    Ok(cfg)
}

/// Whether the board images' Ping360 settings (`Ping360Config::BOARD`: they take no command
/// line) are the scenario's `cfg`; else the key to change and why.
pub fn board_config_matches(cfg: &Ping360Config) -> Result<(), (&'static str, String)> {
    let b = Ping360Config::BOARD;
    let why = |key, what: String| {
        Err((
            key,
            format!("the board images drive their Ping360 with {what} (Ping360Config::BOARD; use --firmware host for other settings)"),
        ))
    };
    if cfg.step_grad != b.step_grad {
        return why(
            "step_deg",
            format!(
                "a step of {} gradians ({:.1}°)",
                b.step_grad,
                f32::from(b.step_grad) * 0.9
            ),
        );
    }
    if cfg.samples != b.samples {
        return why("bins", format!("{} samples", b.samples));
    }
    if *cfg != b {
        return why("range_m", format!("a range of {} m", b.range_m()));
    }
    Ok(())
}

/// The host-process firmware's arguments for `cfg` on the pty `device`.
pub fn firmware_args(device: &Path, cfg: &Ping360Config) -> Vec<std::ffi::OsString> {
    let mut a: Vec<std::ffi::OsString> = vec!["--ping360".into(), device.into()];
    for (k, v) in [
        ("--ping360-step", cfg.step_grad.to_string()),
        ("--ping360-samples", cfg.samples.to_string()),
        ("--ping360-range", cfg.range_m().to_string()),
        ("--sound-speed", cfg.sound_speed.to_string()),
        ("--ping360-timeout-ms", cfg.timeout_ms.to_string()),
    ] {
        a.push(k.into());
        a.push(v.into());
    }
    a
}

/// What the simulated Ping360 did, for the summary and the tests.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SimCounts {
    /// `transducer` commands received.
    pub commands: u32,
    /// `device_data` answers written.
    pub answers: u32,
    /// Answers the firmware's decoder drops (corrupted on the way, per the mirror).
    pub refused: u32,
    /// Commands left unanswered (a sonar dropout, or answers dropped on the line).
    pub unanswered: u32,
    /// Answers corrupted on the line that the firmware's decoder still accepts: bit errors the
    /// Ping protocol's 16-bit sum does not catch (two flips of one bit position that cancel).
    pub corrupted_accepted: u32,
}

/// The simulated Ping360 of one vehicle.
pub struct SimPing360 {
    port: File,
    cfg: Ping360Config,
    from_fw: Decoder,
    /// The firmware's driver as the firmware runs it, fed the same bytes and periods.
    mirror: Ping360,
    /// Time of the last period, ms (the firmware's time when it reads the answers).
    last_tick_ms: u64,
    /// The newest command and when its answer is due, s.
    pending: Option<(TransducerRepr, f64)>,
    overhead_s: f64,
    raw: Option<(BufWriter<File>, u64)>,
    /// What it did.
    pub counts: SimCounts,
}

impl SimPing360 {
    /// A sonar on the pty master `port`, mounted and set as the firmware's `cfg` says, taking
    /// `overhead_s` per ping for the head's step; logging what it sends to `raw_log` if given.
    pub fn new(
        port: File,
        cfg: Ping360Config,
        overhead_s: f64,
        raw_log: Option<&Path>,
    ) -> std::io::Result<Self> {
        let raw = match raw_log {
            Some(p) => Some((BufWriter::new(File::create(p)?), 0)),
            None => None,
        };
        let mirror = Ping360::new(cfg).map_err(|e| std::io::Error::other(e.to_string()))?;
        Ok(SimPing360 {
            port,
            cfg,
            from_fw: Decoder::new(),
            mirror,
            last_tick_ms: 0,
            pending: None,
            overhead_s,
            raw,
            counts: SimCounts::default(),
        })
    }

    /// Time from a command to its data having arrived, s; and from the command to the ping.
    fn timing(&self, cmd: &TransducerRepr) -> (f64, f64) {
        let s = cmd.settings;
        let n = f64::from(s.number_of_samples);
        let listen = n * f64::from(s.sample_period) * 25e-9;
        let frame = 8.0 + 14.0 + n + 2.0;
        let transfer = frame * 10.0 / BAUD;
        (self.overhead_s + listen + transfer, self.overhead_s)
    }

    /// Reads what the firmware sent, waiting at most `wait_ms` for the first bytes; each
    /// `transducer` becomes the pending command, sent at `sent_at` s.
    fn read(&mut self, wait_ms: i32, sent_at: f64) -> std::io::Result<usize> {
        // A failed wait counts as nothing to read, as a quiet line does.
        if !crate::firmware::readable(&self.port, wait_ms).unwrap_or(false) {
            return Ok(0);
        }
        let mut buf = [0u8; 1024];
        let n = match self.port.read(&mut buf) {
            Ok(n) => n,
            Err(e) if e.kind() == std::io::ErrorKind::WouldBlock => 0,
            Err(e) if e.raw_os_error() == Some(nix::errno::Errno::EIO as i32) => 0,
            Err(e) => return Err(e),
        };
        let mut rest = &buf[..n];
        while !rest.is_empty() {
            let (used, ev) = self.from_fw.feed(rest);
            rest = &rest[used..];
            if let Event::Frame(h) = ev {
                let cmd = self
                    .from_fw
                    .payload()
                    .and_then(|p| Message::parse(h.message_id, p).ok());
                if let Some(Message::Transducer(t)) = cmd {
                    self.counts.commands += 1;
                    if self.pending.is_some() {
                        self.counts.unanswered += 1;
                    }
                    let due = sent_at + self.timing(&t).0;
                    self.pending = Some((t, due));
                }
            }
        }
        Ok(n)
    }

    /// Reads every command the firmware has sent: in lockstep until `expected` have come
    /// (the count its last telemetry gave), else what is there. Commands read now were sent at
    /// `sent_at` s (the last period's time).
    pub fn sync(&mut self, expected: u32, sent_at: f64, lockstep: bool) -> std::io::Result<()> {
        let start = Instant::now();
        loop {
            let wait = if lockstep && self.counts.commands < expected {
                10
            } else {
                0
            };
            let n = self.read(wait, sent_at)?;
            if n == 0 && !(lockstep && self.counts.commands < expected) {
                return Ok(());
            }
            if start.elapsed() > ANSWER_WAIT {
                return Err(std::io::Error::new(
                    std::io::ErrorKind::TimedOut,
                    format!(
                        "the firmware counted {expected} Ping360 commands, {} came",
                        self.counts.commands
                    ),
                ));
            }
        }
    }

    /// Answers the commands due by `t` s: renders each ping with `sonar` from the vehicle's
    /// state `truth` at `t`, writes the `device_data` through `tap` (faults, counts), and in
    /// lockstep waits for the command the firmware sends when it accepts the data. During a
    /// sonar dropout (`silent`) the command due goes unanswered.
    #[allow(clippy::too_many_arguments)]
    pub fn answer(
        &mut self,
        t: f64,
        truth: &VehicleState,
        obstacles: &[SimObstacle],
        others: &[(P2, f64)],
        sonar: &mut Sonar,
        tap: &mut dyn Tap,
        lockstep: bool,
        silent: bool,
    ) -> std::io::Result<()> {
        while let Some((cmd, due)) = self.pending.filter(|(_, due)| *due <= t + 1e-9) {
            self.pending = None;
            if silent {
                self.counts.unanswered += 1;
                continue;
            }
            let frame = self.render(&cmd, due, t, truth, obstacles, others, sonar)?;
            let Some(bytes) = tap.outgoing(&frame) else {
                self.counts.unanswered += 1;
                continue;
            };
            self.port.write_all(&bytes)?;
            self.counts.answers += 1;
            self.log(&bytes);
            let (accepted, answered) = self.mirror_feed(&bytes);
            if !accepted {
                self.counts.refused += 1;
            } else if bytes != frame {
                self.counts.corrupted_accepted += 1;
            }
            if answered && lockstep {
                let before = self.counts.commands;
                let start = Instant::now();
                while self.counts.commands == before {
                    self.read(10, due)?;
                    if start.elapsed() > ANSWER_WAIT {
                        return Err(std::io::Error::new(
                            std::io::ErrorKind::TimedOut,
                            "the firmware sent no Ping360 command after accepting data",
                        ));
                    }
                }
            } else if !lockstep {
                self.read(0, due)?;
            }
        }
        Ok(())
    }

    /// The `device_data` frame answering `cmd`, its data in by `due` s.
    #[allow(clippy::too_many_arguments)]
    fn render(
        &mut self,
        cmd: &TransducerRepr,
        due: f64,
        t: f64,
        truth: &VehicleState,
        obstacles: &[SimObstacle],
        others: &[(P2, f64)],
        sonar: &mut Sonar,
    ) -> std::io::Result<Vec<u8>> {
        let s = cmd.settings;
        let (total, to_ping) = self.timing(cmd);
        let tp = due - total + to_ping;
        let n = usize::from(s.number_of_samples);
        let range = n as f64 * f64::from(s.sample_m(SOUND_SPEED as f32));
        let bearing = f64::from(self.cfg.bearing_rad(s.angle));
        let data = if cmd.transmit {
            sonar
                .ping_along(tp, t, truth, bearing, range, n, obstacles, others)
                .bins
        } else {
            Vec::new()
        };
        let m = Message::DeviceData(DeviceDataRepr {
            settings: s,
            data: &data,
        });
        let mut buf = vec![0u8; 8 + m.payload_len() + 2];
        let len =
            emit_frame(&m, 2, 0, &mut buf).map_err(|e| std::io::Error::other(e.to_string()))?;
        buf.truncate(len);
        Ok(buf)
    }

    /// Feeds `bytes` to the mirror of the firmware's driver: whether it turns them into a
    /// scanline, and whether it sends a command in answer.
    fn mirror_feed(&mut self, bytes: &[u8]) -> (bool, bool) {
        let before = self.mirror.counters();
        let mut sent = false;
        self.mirror.on_bytes(
            bytes,
            self.last_tick_ms,
            None,
            &mut |_| {
                sent = true;
                true
            },
            &mut |_, _| {},
        );
        (self.mirror.counters().data > before.data, sent)
    }

    /// The firmware ran its period at `t_ms` (its driver's timeouts and first command).
    pub fn tick(&mut self, t_ms: u64) {
        self.last_tick_ms = t_ms;
        self.mirror.poll(t_ms, &mut |_| true);
    }

    fn log(&mut self, bytes: &[u8]) {
        if let Some((w, written)) = self.raw.as_mut() {
            if *written + bytes.len() as u64 <= MAX_RAW_LOG_BYTES && w.write_all(bytes).is_ok() {
                *written += bytes.len() as u64;
            }
        }
    }

    /// Flushes the raw log.
    pub fn finish(&mut self) -> std::io::Result<()> {
        if let Some((w, _)) = self.raw.as_mut() {
            w.flush()?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scenario::Sonar as Spec;

    #[test]
    fn the_shipped_scenarios_ping360_is_the_boards() {
        // `ping360_narrow_gap.toml`'s sonar: QEMU's image drives it with the same settings.
        let spec = Spec {
            range_m: 30.0,
            bins: 300,
            step: 1.8f64.to_radians(),
            ..Spec::default()
        };
        let cfg = firmware_config(&spec).unwrap();
        assert_eq!(cfg, Ping360Config::BOARD);
        assert_eq!(board_config_matches(&cfg), Ok(()));
        let other = firmware_config(&Spec { bins: 600, ..spec }).unwrap();
        assert_eq!(board_config_matches(&other).unwrap_err().0, "bins");
    }

    #[test]
    fn scenario_settings_map_to_the_driver() {
        // The scenario default: 20 m in 3.6° (4-gradian) steps over 300 samples.
        let spec = Spec::default();
        let cfg = firmware_config(&spec).unwrap();
        assert_eq!((cfg.step_grad, cfg.samples), (4, 300));
        assert!((cfg.range_m() - 20.0).abs() < 0.01);
        let bad = Spec {
            step: 1.0f64.to_radians(),
            ..spec
        };
        assert_eq!(firmware_config(&bad).unwrap_err().0, "step_deg");
        let bad = Spec { bins: 100, ..spec };
        assert_eq!(firmware_config(&bad).unwrap_err().0, "bins");
        let args = firmware_args(Path::new("/dev/pts/9"), &cfg);
        assert_eq!(args[0], "--ping360");
        assert_eq!(args[1], "/dev/pts/9");
    }
}
