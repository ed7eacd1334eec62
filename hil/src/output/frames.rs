//! `frames_<vehicle>.log`: the serial traffic between the harness and one firmware, one line per
//! chunk of bytes as it was written or read:
//!
//! ```text
//! # frames of vehicle alpha: t_s, direction (> to firmware, < from firmware), bytes in hex
//! 0.1 > 03 01 02 00
//! 0.13 < 05 82 11 22 33 00
//! ```
//!
//! The time is Rust's shortest round-trip form of the simulation time in seconds, so
//! [`FrameLog::replay`] gives back exactly what was logged. Lines starting with `#` and blank
//! lines are comments.
//!
//! A log stops at [`MAX_FRAME_LOG_BYTES`]: a long run of many vehicles would otherwise fill the
//! disk (a day of 9 vehicles at 50 Hz is about 53 GB). Its last line then says where it
//! stopped, the harness says so once on stderr, and the log replays as the run's first part.

use std::fmt::Write as _;
use std::io::{BufRead, BufWriter, Write};
use std::path::Path;

/// Direction of a chunk on the link.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Dir {
    /// Harness → firmware (`>`).
    ToFirmware,
    /// Firmware → harness (`<`).
    FromFirmware,
}

impl Dir {
    /// The log's symbol.
    pub fn symbol(self) -> char {
        match self {
            Dir::ToFirmware => '>',
            Dir::FromFirmware => '<',
        }
    }
}

/// Largest frame log, bytes, per vehicle: 256 MiB, some 200 000 periods of a VideoRay with its
/// sonar (0.9–1.4 kB of hex per period), hours at 10 Hz. A run of [`MAX_VEHICLES`] writes at
/// most 9 times this.
///
/// [`MAX_VEHICLES`]: crate::scenario::MAX_VEHICLES
pub const MAX_FRAME_LOG_BYTES: u64 = 256 << 20;

/// A writer of one vehicle's frame log.
#[derive(Debug)]
pub struct FrameLog {
    out: BufWriter<std::fs::File>,
    line: String,
    path: std::path::PathBuf,
    /// Bytes written so far, and the most this log may hold.
    written: u64,
    limit: u64,
    truncated: bool,
}

impl FrameLog {
    /// Creates (truncates) `dir/frames_<vehicle>.log`, the vehicle name made file-safe with
    /// [`super::file_stem`].
    /// The log stops at [`MAX_FRAME_LOG_BYTES`].
    pub fn create(dir: &Path, vehicle_name: &str) -> std::io::Result<FrameLog> {
        Self::create_with_limit(dir, vehicle_name, MAX_FRAME_LOG_BYTES)
    }

    /// [`FrameLog::create`], stopping at `limit` bytes instead.
    pub fn create_with_limit(
        dir: &Path,
        vehicle_name: &str,
        limit: u64,
    ) -> std::io::Result<FrameLog> {
        let path = dir.join(format!("frames_{}.log", super::file_stem(vehicle_name)));
        let mut out = BufWriter::new(std::fs::File::create(&path)?);
        // The name may hold anything; keep the comment on one line.
        let name: String = vehicle_name.chars().filter(|c| !c.is_control()).collect();
        let header = format!(
            "# frames of vehicle {name}: t_s, direction (> to firmware, < from firmware), bytes in hex\n"
        );
        out.write_all(header.as_bytes())?;
        Ok(FrameLog {
            out,
            line: String::new(),
            path,
            written: header.len() as u64,
            limit,
            truncated: false,
        })
    }

    /// Logs one chunk of bytes seen at simulation time `t_s`; past the limit, notes once where
    /// the log stopped and drops the rest.
    pub fn log(&mut self, t_s: f64, dir: Dir, bytes: &[u8]) -> std::io::Result<()> {
        if self.truncated {
            return Ok(());
        }
        self.line.clear();
        // Writing to a String cannot fail.
        let _ = write!(self.line, "{t_s} {}", dir.symbol());
        for b in bytes {
            let _ = write!(self.line, " {b:02x}");
        }
        self.line.push('\n');
        if self.written + self.line.len() as u64 > self.limit {
            self.truncated = true;
            let note = format!(
                "reached its limit of {} bytes at t = {t_s} s; later traffic is not logged",
                self.limit
            );
            eprintln!("hil: {} {note}", self.path.display());
            return writeln!(self.out, "# truncated: this log {note}");
        }
        self.written += self.line.len() as u64;
        self.out.write_all(self.line.as_bytes())
    }

    /// Whether the log reached its limit and stopped.
    pub fn truncated(&self) -> bool {
        self.truncated
    }

    /// Flushes buffered lines to the file (also done on drop, where errors are lost).
    pub fn flush(&mut self) -> std::io::Result<()> {
        self.out.flush()
    }

    /// Reads a frame log back: (time, direction, bytes) per line, in file order.
    pub fn replay(path: &Path) -> std::io::Result<Vec<(f64, Dir, Vec<u8>)>> {
        let file = std::io::BufReader::new(std::fs::File::open(path)?);
        let mut chunks = Vec::new();
        for (i, line) in file.lines().enumerate() {
            let line = line?;
            let text = line.trim();
            if text.is_empty() || text.starts_with('#') {
                continue;
            }
            let bad = |what: &str| {
                std::io::Error::new(
                    std::io::ErrorKind::InvalidData,
                    format!("{}:{}: {what}: {text:?}", path.display(), i + 1),
                )
            };
            let mut words = text.split_ascii_whitespace();
            let t = words
                .next()
                .and_then(|w| w.parse::<f64>().ok())
                .ok_or_else(|| bad("expected a time in seconds"))?;
            let dir = match words.next() {
                Some(">") => Dir::ToFirmware,
                Some("<") => Dir::FromFirmware,
                _ => return Err(bad("expected `>` or `<`")),
            };
            let bytes = words
                .map(|w| {
                    // from_str_radix alone would take "+f".
                    if w.len() == 2 && w.bytes().all(|c| c.is_ascii_hexdigit()) {
                        u8::from_str_radix(w, 16).ok()
                    } else {
                        None
                    }
                })
                .collect::<Option<Vec<u8>>>()
                .ok_or_else(|| bad("expected two-digit hex bytes"))?;
            chunks.push((t, dir, bytes));
        }
        Ok(chunks)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn temp_dir(tag: &str) -> std::path::PathBuf {
        let d = std::env::temp_dir().join(format!("hil-frames-{tag}-{}", std::process::id()));
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    #[test]
    fn round_trip() {
        let dir = temp_dir("rt");
        let chunks: Vec<(f64, Dir, Vec<u8>)> = vec![
            (0.0, Dir::ToFirmware, vec![0x00, 0x01, 0xff]),
            (0.1 + 0.2, Dir::FromFirmware, (0..=255).collect()),
            (1e-9, Dir::FromFirmware, vec![]),
            (12345.678901234, Dir::ToFirmware, vec![0xab]),
        ];
        {
            let mut log = FrameLog::create(&dir, "al pha\nx").unwrap();
            for (t, d, b) in &chunks {
                log.log(*t, *d, b).unwrap();
            }
            log.flush().unwrap();
        }
        let path = dir.join("frames_al_pha_x.log");
        assert_eq!(FrameLog::replay(&path).unwrap(), chunks);
        let text = std::fs::read_to_string(&path).unwrap();
        assert_eq!(text.lines().count(), 5);
        assert!(text.lines().nth(1).unwrap() == "0 > 00 01 ff");
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn replay_refuses_malformed_lines_with_the_line_number() {
        let dir = temp_dir("bad");
        let path = dir.join("f.log");
        for (text, line) in [
            ("# c\n0.5 > 0g\n", ":2:"),
            ("x > 00\n", ":1:"),
            ("\n\n1 = 00\n", ":3:"),
            ("1 < 000\n", ":1:"),
        ] {
            std::fs::write(&path, text).unwrap();
            let e = FrameLog::replay(&path).unwrap_err();
            assert_eq!(e.kind(), std::io::ErrorKind::InvalidData);
            assert!(e.to_string().contains(line), "{e}");
        }
        std::fs::write(&path, "").unwrap();
        assert!(FrameLog::replay(&path).unwrap().is_empty());
        let _ = std::fs::remove_dir_all(&dir);
    }
}
