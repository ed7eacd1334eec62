//! `Log` (0x84): a diagnostic text line.

use super::field::log;
use crate::link::codec::{refuse, Reader, Writer};
use crate::link::frame::MessageType;
use crate::link::payload::Payload;
use crate::link::{Error, Problem, MAX_LOG_LEN};

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
        let level = LogLevel::from_code(level).ok_or(log::LEVEL.error(Problem::UnknownCode))?;
        if text.len() > MAX_LOG_LEN {
            return refuse(log::TEXT, Problem::OutOfRange);
        }
        let text = core::str::from_utf8(text).map_err(|_| log::TEXT.error(Problem::Invalid))?;
        Ok(LogRepr { level, text })
    }

    fn payload_len(&self) -> usize {
        1 + self.text.len()
    }

    fn emit(&self, out: &mut [u8]) -> Result<usize, Error> {
        if self.text.len() > MAX_LOG_LEN {
            return refuse(log::TEXT, Problem::OutOfRange);
        }
        let mut w = Writer::new(out);
        w.u8(self.level as u8)?;
        w.bytes(self.text.as_bytes())?;
        Ok(w.len())
    }
}
