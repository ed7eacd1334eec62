//! The text dumps Blue Robotics' `brping` Python decoder prints for `device_data` messages,
//! read back into messages and rebuilt into the binary frames the sonar sent.
//!
//! One message looks like (the 1200 samples shortened):
//!
//! ```text
//! ID: 2300 - device_data
//! Header: start_1: 66 start_2: 82 payload_length: 1214 message_id: 2300 src_device_id: 2 dst_device_id: 0
//! Payload:
//!   - mode: 0
//!   - gain_setting: 0
//!   - angle: 150
//!   - transmit_duration: 16
//!   - sample_period: 90
//!   - transmit_frequency: 1000
//!   - number_of_samples: 1200
//!   - data_length: 1200
//!   - data: ['0x4c', '0x98', ...]
//! Checksum: 17245 check: 17245 pass: True
//! ```
//!
//! Every field is required; a message missing one, or with a number that does not fit its
//! type, is an error naming the message and the field. The checksum logged by the decoder that
//! wrote the dump is kept: rebuilding the frame must reproduce it.

use std::path::PathBuf;

use vpf::link::ping::{emit_frame, DeviceDataRepr, Message, PingSettings};

/// Largest dump read, bytes (the recording of 101 messages is 1 MB).
pub const MAX_DUMP_BYTES: u64 = 256 << 20;

/// Why a dump does not read, or a message of it does not rebuild.
#[derive(Debug, thiserror::Error)]
pub enum DumpError {
    /// Message `message` (0-based, in file order) lacks `field`.
    #[error("message {message}: no `{field}`")]
    Missing {
        /// Which message.
        message: usize,
        /// The field, as the dump names it.
        field: &'static str,
    },
    /// A field's value is not a number of its type.
    #[error("message {message}: `{field}` is not a number that fits")]
    NotANumber {
        /// Which message.
        message: usize,
        /// The field, as the dump names it.
        field: &'static str,
    },
    /// The `data` list has no closing `]`.
    #[error("message {message}: `data` is not closed")]
    Unclosed {
        /// Which message.
        message: usize,
    },
    /// An item of the `data` list is not a byte.
    #[error("message {message}: data item `{item}` is not a byte")]
    NotAByte {
        /// Which message.
        message: usize,
        /// The item as written.
        item: String,
    },
    /// The firmware's encoder refused the message.
    #[error("the frame does not rebuild: {0}")]
    Encode(#[from] vpf::link::ping::Error),
    /// The file could not be read.
    #[error("{}: {source}", path.display())]
    Io {
        /// The dump.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// The file is larger than [`MAX_DUMP_BYTES`].
    #[error("{}: larger than {MAX_DUMP_BYTES} bytes", path.display())]
    TooLarge {
        /// The dump.
        path: PathBuf,
    },
    /// A message of the file does not read.
    #[error("{}: {source}", path.display())]
    In {
        /// The dump.
        path: PathBuf,
        /// Why.
        source: Box<DumpError>,
    },
}

/// One `device_data` message of a dump.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct DumpMessage {
    /// Header: `payload_length`.
    pub payload_length: u16,
    /// Header: `message_id`.
    pub message_id: u16,
    /// Header: `src_device_id`.
    pub src: u8,
    /// Header: `dst_device_id`.
    pub dst: u8,
    /// The payload's settings.
    pub settings: PingSettings,
    /// `data_length` as logged.
    pub data_length: u16,
    /// The samples.
    pub data: Vec<u8>,
    /// `Checksum: N` as logged.
    pub checksum: u16,
    /// `pass: True` as logged.
    pub pass: bool,
}

impl DumpMessage {
    /// The binary frame the sonar sent, rebuilt with the firmware's own encoder.
    pub fn frame(&self) -> Result<Vec<u8>, DumpError> {
        let m = Message::DeviceData(DeviceDataRepr {
            settings: self.settings,
            data: &self.data,
        });
        let mut buf = vec![0u8; 8 + m.payload_len() + 2];
        let n = emit_frame(&m, self.src, self.dst, &mut buf)?;
        buf.truncate(n);
        Ok(buf)
    }
}

/// The value after `key` (e.g. `"angle:"`) in `text`, as a number of type `T`.
fn field<T: std::str::FromStr>(
    text: &str,
    key: &'static str,
    which: usize,
) -> Result<T, DumpError> {
    let at = text.find(key).ok_or(DumpError::Missing {
        message: which,
        field: key,
    })?;
    let rest = text[at + key.len()..].trim_start();
    let end = rest
        .find(|c: char| !c.is_ascii_digit())
        .unwrap_or(rest.len());
    rest[..end].parse().map_err(|_| DumpError::NotANumber {
        message: which,
        field: key,
    })
}

/// Parses every `device_data` message of a dump, in order.
pub fn parse(text: &str) -> Result<Vec<DumpMessage>, DumpError> {
    let mut out = Vec::new();
    for (i, block) in text.split("ID: 2300 - device_data").skip(1).enumerate() {
        let data_at = block.find("- data:").ok_or(DumpError::Missing {
            message: i,
            field: "data",
        })?;
        let list_end = block[data_at..]
            .find(']')
            .ok_or(DumpError::Unclosed { message: i })?;
        let list = &block[data_at + "- data:".len()..data_at + list_end];
        let data = list
            .split(',')
            .map(|s| s.trim().trim_start_matches('[').trim_matches('\''))
            .filter(|s| !s.is_empty())
            .map(|s| {
                u8::from_str_radix(s.trim_start_matches("0x"), 16).map_err(|_| {
                    DumpError::NotAByte {
                        message: i,
                        item: s.to_string(),
                    }
                })
            })
            .collect::<Result<Vec<u8>, DumpError>>()?;
        let head = &block[..data_at];
        let tail = &block[data_at + list_end..];
        let settings = PingSettings {
            mode: field(head, "- mode:", i)?,
            gain_setting: field(head, "- gain_setting:", i)?,
            angle: field(head, "- angle:", i)?,
            transmit_duration: field(head, "- transmit_duration:", i)?,
            sample_period: field(head, "- sample_period:", i)?,
            transmit_frequency: field(head, "- transmit_frequency:", i)?,
            number_of_samples: field(head, "- number_of_samples:", i)?,
        };
        out.push(DumpMessage {
            payload_length: field(head, "payload_length:", i)?,
            message_id: field(head, "message_id:", i)?,
            src: field(head, "src_device_id:", i)?,
            dst: field(head, "dst_device_id:", i)?,
            settings,
            data_length: field(head, "- data_length:", i)?,
            data,
            checksum: field(tail, "Checksum:", i)?,
            pass: tail.contains("pass: True"),
        });
    }
    Ok(out)
}

/// Reads a dump file (at most [`MAX_DUMP_BYTES`]).
pub fn read(path: &std::path::Path) -> Result<Vec<DumpMessage>, DumpError> {
    use std::io::Read;
    let io = |source| DumpError::Io {
        path: path.to_path_buf(),
        source,
    };
    let f = std::fs::File::open(path).map_err(io)?;
    let mut text = String::new();
    f.take(MAX_DUMP_BYTES + 1)
        .read_to_string(&mut text)
        .map_err(io)?;
    if text.len() as u64 > MAX_DUMP_BYTES {
        return Err(DumpError::TooLarge {
            path: path.to_path_buf(),
        });
    }
    parse(&text).map_err(|e| DumpError::In {
        path: path.to_path_buf(),
        source: Box::new(e),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    const ONE: &str = "\"<bound method PingMessage.unpack_msg_data of \n\n---\nID: 2300 - device_data\n\
Header: start_1: 66 start_2: 82 payload_length: 18 message_id: 2300 src_device_id: 2 dst_device_id: 0\n\
Payload:\n  - mode: 0\n  - gain_setting: 0\n  - angle: 150\n  - transmit_duration: 16\n  - sample_period: 90\n\
  - transmit_frequency: 1000\n  - number_of_samples: 1200\n  - data_length: 4\n  - data: ['0x4c', '0x98', '0xc9', '0xe4']\n\
Checksum: 1760 check: 1760 pass: True>\"";

    #[test]
    fn a_message_parses_and_rebuilds() {
        let m = parse(ONE).unwrap();
        assert_eq!(m.len(), 1);
        let m = &m[0];
        assert_eq!(
            (m.payload_length, m.message_id, m.src, m.dst),
            (18, 2300, 2, 0)
        );
        assert_eq!(m.settings.angle, 150);
        assert_eq!(m.data, [0x4c, 0x98, 0xc9, 0xe4]);
        let f = m.frame().unwrap();
        assert_eq!(f.len(), 8 + 18 + 2);
        // The sum of the 26 bytes, worked by hand: header 66+82+18+0+(2300 = 0x08FC: 252+8)+2+0
        // = 428; settings 0+0+150+0+16+0+90+0+(1000 = 0x03E8: 232+3)+(1200 = 0x04B0: 176+4)
        // = 671; data length 4; samples 76+152+201+228 = 657. 428+671+4+657 = 1760.
        assert_eq!(u16::from_le_bytes([f[26], f[27]]), 1760);
        assert_eq!(m.checksum, 1760);
        assert!(m.pass);
    }

    #[test]
    fn a_missing_field_is_named() {
        let broken = ONE.replace("  - angle: 150\n", "");
        let e = parse(&broken).unwrap_err();
        assert_eq!(e.to_string(), "message 0: no `- angle:`");
        assert!(matches!(
            e,
            DumpError::Missing {
                message: 0,
                field: "- angle:"
            }
        ));
        let broken = ONE.replace("'0x98'", "'0xzz'");
        assert!(parse(&broken).unwrap_err().to_string().contains("0xzz"));
    }
}
