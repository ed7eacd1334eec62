//! The common messages (ids below 1000, every Ping device speaks them) that a driver needs.
//!
//! | id | message | payload |
//! |---|---|---|
//! | 1 | `ack` | `acked_id` u16 |
//! | 2 | `nack` | `nacked_id` u16 · `nack_message` ASCII, not necessarily NUL-terminated |
//! | 5 | `protocol_version` | `version_major` u8 · `version_minor` u8 · `version_patch` u8 · `reserved` u8 |
//! | 6 | `general_request` | `requested_id` u16 |

use super::{get_u16, put_u16, Error};

/// `ack` (1): the device acknowledges a message.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct AckRepr {
    /// The id of the message acknowledged.
    pub acked_id: u16,
}

impl AckRepr {
    /// Payload length.
    pub const LEN: usize = 2;

    /// Parses a payload of exactly [`Self::LEN`] bytes.
    pub fn parse(payload: &[u8]) -> Result<Self, Error> {
        match payload {
            [a, b] => Ok(AckRepr {
                acked_id: u16::from_le_bytes([*a, *b]),
            }),
            _ => Err(Error::Length),
        }
    }

    /// Writes the payload; returns its length.
    pub fn emit(&self, out: &mut [u8]) -> Result<usize, Error> {
        put_u16(out, 0, self.acked_id)
            .then_some(Self::LEN)
            .ok_or(Error::BufferTooSmall)
    }
}

/// `nack` (2): the device refuses a message, and says why in ASCII.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct NackRepr<'a> {
    /// The id of the message refused.
    pub nacked_id: u16,
    /// The reason, as sent (ASCII; a trailing NUL, if any, is kept).
    pub text: &'a [u8],
}

impl<'a> NackRepr<'a> {
    /// Parses a payload of at least 2 bytes.
    pub fn parse(payload: &'a [u8]) -> Result<Self, Error> {
        let nacked_id = get_u16(payload, 0).ok_or(Error::Length)?;
        Ok(NackRepr {
            nacked_id,
            text: payload.get(2..).unwrap_or(&[]),
        })
    }

    /// Payload length.
    pub fn payload_len(&self) -> usize {
        2 + self.text.len()
    }

    /// Writes the payload; returns its length.
    pub fn emit(&self, out: &mut [u8]) -> Result<usize, Error> {
        let len = self.payload_len();
        let dst = out.get_mut(..len).ok_or(Error::BufferTooSmall)?;
        put_u16(dst, 0, self.nacked_id);
        if let Some(t) = dst.get_mut(2..) {
            t.copy_from_slice(self.text);
        }
        Ok(len)
    }
}

/// `protocol_version` (5): the version of the Ping protocol the device speaks.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ProtocolVersionRepr {
    /// `version_major`.
    pub major: u8,
    /// `version_minor`.
    pub minor: u8,
    /// `version_patch`.
    pub patch: u8,
}

impl ProtocolVersionRepr {
    /// Payload length (the fourth byte is reserved: written 0, read and ignored).
    pub const LEN: usize = 4;

    /// Parses a payload of exactly [`Self::LEN`] bytes.
    pub fn parse(payload: &[u8]) -> Result<Self, Error> {
        match payload {
            [major, minor, patch, _reserved] => Ok(ProtocolVersionRepr {
                major: *major,
                minor: *minor,
                patch: *patch,
            }),
            _ => Err(Error::Length),
        }
    }

    /// Writes the payload; returns its length.
    pub fn emit(&self, out: &mut [u8]) -> Result<usize, Error> {
        let dst = out.get_mut(..Self::LEN).ok_or(Error::BufferTooSmall)?;
        dst.copy_from_slice(&[self.major, self.minor, self.patch, 0]);
        Ok(Self::LEN)
    }
}

/// `general_request` (6): asks the device to send the message `requested_id` (a "get").
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct GeneralRequestRepr {
    /// The id of the message wanted.
    pub requested_id: u16,
}

impl GeneralRequestRepr {
    /// Payload length.
    pub const LEN: usize = 2;

    /// Parses a payload of exactly [`Self::LEN`] bytes.
    pub fn parse(payload: &[u8]) -> Result<Self, Error> {
        match payload {
            [a, b] => Ok(GeneralRequestRepr {
                requested_id: u16::from_le_bytes([*a, *b]),
            }),
            _ => Err(Error::Length),
        }
    }

    /// Writes the payload; returns its length.
    pub fn emit(&self, out: &mut [u8]) -> Result<usize, Error> {
        put_u16(out, 0, self.requested_id)
            .then_some(Self::LEN)
            .ok_or(Error::BufferTooSmall)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ack_bytes() {
        // acked_id 2601 (transducer) = 0x0A29.
        let bytes = [0x29, 0x0A];
        let a = AckRepr::parse(&bytes).unwrap();
        assert_eq!(a.acked_id, 2601);
        let mut out = [0u8; 2];
        assert_eq!(a.emit(&mut out), Ok(2));
        assert_eq!(out, bytes);
        assert_eq!(AckRepr::parse(&bytes[..1]), Err(Error::Length));
        assert_eq!(AckRepr::parse(&[0, 0, 0]), Err(Error::Length));
        assert_eq!(a.emit(&mut out[..1]), Err(Error::BufferTooSmall));
    }

    #[test]
    fn nack_bytes() {
        let bytes = [0x29, 0x0A, b'b', b'a', b'd', 0];
        let n = NackRepr::parse(&bytes).unwrap();
        assert_eq!(n.nacked_id, 2601);
        assert_eq!(n.text, b"bad\0");
        let mut out = [0u8; 6];
        assert_eq!(n.emit(&mut out), Ok(6));
        assert_eq!(out, bytes);
        // No text is a valid nack; no id is not.
        assert_eq!(NackRepr::parse(&bytes[..2]).unwrap().text, b"");
        assert_eq!(NackRepr::parse(&bytes[..1]), Err(Error::Length));
        assert_eq!(n.emit(&mut out[..5]), Err(Error::BufferTooSmall));
    }

    #[test]
    fn protocol_version_and_general_request_bytes() {
        let v = ProtocolVersionRepr::parse(&[1, 2, 3, 0xEE]).unwrap();
        assert_eq!((v.major, v.minor, v.patch), (1, 2, 3));
        let mut out = [0xFFu8; 4];
        assert_eq!(v.emit(&mut out), Ok(4));
        assert_eq!(out, [1, 2, 3, 0]);
        assert_eq!(ProtocolVersionRepr::parse(&[1, 2, 3]), Err(Error::Length));
        let g = GeneralRequestRepr::parse(&[0x05, 0x00]).unwrap();
        assert_eq!(g.requested_id, 5);
        let mut out = [0u8; 2];
        assert_eq!(g.emit(&mut out), Ok(2));
        assert_eq!(out, [5, 0]);
    }
}
