//! A Ping protocol frame: a checked view over its bytes, as smoltcp's packet types are.
//!
//! Layout: 0–1 `'B' 'R'` · 2–3 `payload_length` u16 · 4–5 `message_id` u16 ·
//! 6 `src_device_id` u8 · 7 `dst_device_id` u8 · 8.. payload · then `checksum` u16, the sum of
//! all bytes before it modulo 2¹⁶ (little-endian throughout).

use super::message::Message;
use super::{checksum, get_u16, put_u16, Error, CHECKSUM_LEN, HEADER_LEN, MAX_PAYLOAD, START};

/// A frame's header fields, without the start bytes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Header {
    /// Bytes of payload.
    pub payload_len: u16,
    /// What the payload is.
    pub message_id: u16,
    /// Sender's device id.
    pub src: u8,
    /// Recipient's device id.
    pub dst: u8,
}

impl Header {
    /// Parses the 8 header bytes: the start bytes and a payload length within
    /// [`MAX_PAYLOAD`] are checked.
    pub fn parse(bytes: &[u8; HEADER_LEN]) -> Result<Header, Error> {
        let [b, r, l0, l1, i0, i1, src, dst] = *bytes;
        if [b, r] != START {
            return Err(Error::Start);
        }
        let payload_len = u16::from_le_bytes([l0, l1]);
        if usize::from(payload_len) > MAX_PAYLOAD {
            return Err(Error::Oversize);
        }
        Ok(Header {
            payload_len,
            message_id: u16::from_le_bytes([i0, i1]),
            src,
            dst,
        })
    }

    /// The 8 header bytes.
    pub fn to_bytes(&self) -> [u8; HEADER_LEN] {
        let [l0, l1] = self.payload_len.to_le_bytes();
        let [i0, i1] = self.message_id.to_le_bytes();
        [START[0], START[1], l0, l1, i0, i1, self.src, self.dst]
    }

    /// Length of the whole frame: header, payload and checksum.
    pub fn frame_len(&self) -> usize {
        HEADER_LEN + usize::from(self.payload_len) + CHECKSUM_LEN
    }
}

/// A view over the bytes of one frame (extra bytes after it are ignored).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Frame<T: AsRef<[u8]>> {
    buffer: T,
}

impl<T: AsRef<[u8]>> Frame<T> {
    /// A view without checks: the accessors then return `None` or an error rather than panic.
    pub const fn new_unchecked(buffer: T) -> Frame<T> {
        Frame { buffer }
    }

    /// A view of a complete frame: start bytes, a payload length within [`MAX_PAYLOAD`], room
    /// for the payload and checksum, and a checksum that matches.
    pub fn new_checked(buffer: T) -> Result<Frame<T>, Error> {
        let f = Frame::new_unchecked(buffer);
        f.check_len()?;
        if f.checksum() != f.compute_checksum() {
            return Err(Error::Checksum);
        }
        Ok(f)
    }

    /// Checks the start bytes, the payload length and that the buffer holds the frame.
    pub fn check_len(&self) -> Result<(), Error> {
        let h = self.header()?;
        if self.buffer.as_ref().len() < h.frame_len() {
            return Err(Error::Truncated);
        }
        Ok(())
    }

    /// The header fields.
    pub fn header(&self) -> Result<Header, Error> {
        let head: &[u8; HEADER_LEN] = self
            .buffer
            .as_ref()
            .get(..HEADER_LEN)
            .and_then(|h| h.try_into().ok())
            .ok_or(Error::Truncated)?;
        Header::parse(head)
    }

    /// `payload_length`.
    pub fn payload_len(&self) -> u16 {
        get_u16(self.buffer.as_ref(), 2).unwrap_or(0)
    }

    /// `message_id`.
    pub fn message_id(&self) -> u16 {
        get_u16(self.buffer.as_ref(), 4).unwrap_or(0)
    }

    /// `src_device_id`.
    pub fn src(&self) -> u8 {
        self.buffer.as_ref().get(6).copied().unwrap_or(0)
    }

    /// `dst_device_id`.
    pub fn dst(&self) -> u8 {
        self.buffer.as_ref().get(7).copied().unwrap_or(0)
    }

    fn payload_end(&self) -> usize {
        HEADER_LEN + usize::from(self.payload_len())
    }

    /// The payload (empty if the buffer is too short for it).
    pub fn payload(&self) -> &[u8] {
        self.buffer
            .as_ref()
            .get(HEADER_LEN..self.payload_end())
            .unwrap_or(&[])
    }

    /// The checksum field (0 if the buffer is too short for it).
    pub fn checksum(&self) -> u16 {
        get_u16(self.buffer.as_ref(), self.payload_end()).unwrap_or(0)
    }

    /// The checksum the bytes before the checksum field call for.
    pub fn compute_checksum(&self) -> u16 {
        checksum(
            self.buffer
                .as_ref()
                .get(..self.payload_end())
                .unwrap_or(&[]),
        )
    }

    /// The message the frame carries.
    pub fn message(&self) -> Result<Message<'_>, Error> {
        Message::parse(self.message_id(), self.payload())
    }

    /// The underlying buffer.
    pub fn into_inner(self) -> T {
        self.buffer
    }
}

impl<T: AsRef<[u8]> + AsMut<[u8]>> Frame<T> {
    /// Writes the header (start bytes included); `false` if the buffer is too short.
    pub fn set_header(&mut self, h: &Header) -> bool {
        match self.buffer.as_mut().get_mut(..HEADER_LEN) {
            Some(dst) => {
                dst.copy_from_slice(&h.to_bytes());
                true
            }
            None => false,
        }
    }

    /// The payload, writable (empty if the buffer is too short for it).
    pub fn payload_mut(&mut self) -> &mut [u8] {
        let end = self.payload_end();
        self.buffer
            .as_mut()
            .get_mut(HEADER_LEN..end)
            .unwrap_or(&mut [])
    }

    /// Computes and writes the checksum; `false` if the buffer is too short.
    pub fn fill_checksum(&mut self) -> bool {
        let sum = self.compute_checksum();
        let at = self.payload_end();
        put_u16(self.buffer.as_mut(), at, sum)
    }
}

/// Writes `msg` as a whole frame from `src` to `dst` into `out`; returns the frame's length.
pub fn emit_frame(msg: &Message<'_>, src: u8, dst: u8, out: &mut [u8]) -> Result<usize, Error> {
    let payload_len = msg.payload_len();
    if payload_len > MAX_PAYLOAD {
        return Err(Error::Oversize);
    }
    let h = Header {
        // Bounded by MAX_PAYLOAD (1214) just above.
        payload_len: payload_len as u16,
        message_id: msg.message_id(),
        src,
        dst,
    };
    let len = h.frame_len();
    let buf = out.get_mut(..len).ok_or(Error::BufferTooSmall)?;
    let mut f = Frame::new_unchecked(buf);
    f.set_header(&h);
    msg.emit(f.payload_mut())?;
    f.fill_checksum();
    Ok(len)
}

#[cfg(test)]
mod tests {
    use super::super::common::{GeneralRequestRepr, ProtocolVersionRepr};
    use super::*;

    /// The protocol documentation's request: `general_request` for `protocol_version` (id 5).
    const GENERAL_REQUEST_5: [u8; 12] = [
        0x42, 0x52, 0x02, 0x00, 0x06, 0x00, 0x00, 0x00, 0x05, 0x00, 0xa1, 0x00,
    ];
    /// The protocol documentation's answer: `protocol_version` 1.2.3.
    const PROTOCOL_VERSION_123: [u8; 14] = [
        0x42, 0x52, 0x04, 0x00, 0x05, 0x00, 0x00, 0x00, 0x01, 0x02, 0x03, 0x00, 0xa3, 0x00,
    ];

    #[test]
    fn the_documentations_request_parses_and_emits() {
        let f = Frame::new_checked(&GENERAL_REQUEST_5[..]).unwrap();
        assert_eq!(
            f.header(),
            Ok(Header {
                payload_len: 2,
                message_id: 6,
                src: 0,
                dst: 0
            })
        );
        assert_eq!(f.checksum(), 161);
        let m = f.message().unwrap();
        assert_eq!(
            m,
            Message::GeneralRequest(GeneralRequestRepr { requested_id: 5 })
        );
        let mut out = [0u8; 32];
        assert_eq!(emit_frame(&m, 0, 0, &mut out), Ok(12));
        assert_eq!(out[..12], GENERAL_REQUEST_5);
    }

    #[test]
    fn the_documentations_answer_parses_and_emits() {
        let f = Frame::new_checked(&PROTOCOL_VERSION_123[..]).unwrap();
        let m = f.message().unwrap();
        let v = ProtocolVersionRepr {
            major: 1,
            minor: 2,
            patch: 3,
        };
        assert_eq!(m, Message::ProtocolVersion(v));
        let mut out = [0u8; 14];
        assert_eq!(emit_frame(&m, 0, 0, &mut out), Ok(14));
        assert_eq!(out, PROTOCOL_VERSION_123);
        // Too small a buffer is refused, not truncated.
        assert_eq!(
            emit_frame(&m, 0, 0, &mut out[..13]),
            Err(Error::BufferTooSmall)
        );
    }

    #[test]
    fn bad_frames_are_refused_with_their_reason() {
        let mut bad = GENERAL_REQUEST_5;
        bad[8] = 6;
        assert_eq!(Frame::new_checked(&bad[..]), Err(Error::Checksum));
        let mut bad = GENERAL_REQUEST_5;
        bad[0] = b'b';
        assert_eq!(Frame::new_checked(&bad[..]), Err(Error::Start));
        assert_eq!(
            Frame::new_checked(&GENERAL_REQUEST_5[..11]),
            Err(Error::Truncated)
        );
        assert_eq!(Frame::new_checked(&[0x42u8][..]), Err(Error::Truncated));
        // A length past MAX_PAYLOAD: 0xFFFF.
        let mut big = GENERAL_REQUEST_5;
        big[2] = 0xff;
        big[3] = 0xff;
        assert_eq!(Frame::new_checked(&big[..]), Err(Error::Oversize));
        // An unchecked view of nothing answers without panicking.
        let empty = Frame::new_unchecked(&[][..]);
        assert_eq!(
            (empty.payload_len(), empty.message_id(), empty.checksum()),
            (0, 0, 0)
        );
        assert!(empty.payload().is_empty());
    }
}
