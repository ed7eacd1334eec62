//! Every Ping message this module knows, in one enum, parsed by message id.

use super::common::{AckRepr, GeneralRequestRepr, NackRepr, ProtocolVersionRepr};
use super::id;
use super::ping360::{DeviceDataRepr, TransducerRepr, TRANSDUCER_LEN};
use super::Error;

/// A parsed Ping message.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Message<'a> {
    /// `ack` (1).
    Ack(AckRepr),
    /// `nack` (2).
    Nack(NackRepr<'a>),
    /// `protocol_version` (5).
    ProtocolVersion(ProtocolVersionRepr),
    /// `general_request` (6).
    GeneralRequest(GeneralRequestRepr),
    /// Ping360 `device_data` (2300).
    DeviceData(DeviceDataRepr<'a>),
    /// Ping360 `transducer` (2601).
    Transducer(TransducerRepr),
}

impl<'a> Message<'a> {
    /// Parses the payload of a message with id `message_id`.
    pub fn parse(message_id: u16, payload: &'a [u8]) -> Result<Self, Error> {
        Ok(match message_id {
            id::ACK => Message::Ack(AckRepr::parse(payload)?),
            id::NACK => Message::Nack(NackRepr::parse(payload)?),
            id::PROTOCOL_VERSION => Message::ProtocolVersion(ProtocolVersionRepr::parse(payload)?),
            id::GENERAL_REQUEST => Message::GeneralRequest(GeneralRequestRepr::parse(payload)?),
            id::DEVICE_DATA => Message::DeviceData(DeviceDataRepr::parse(payload)?),
            id::TRANSDUCER => Message::Transducer(TransducerRepr::parse(payload)?),
            other => return Err(Error::UnknownId(other)),
        })
    }

    /// Its message id.
    pub fn message_id(&self) -> u16 {
        match self {
            Message::Ack(_) => id::ACK,
            Message::Nack(_) => id::NACK,
            Message::ProtocolVersion(_) => id::PROTOCOL_VERSION,
            Message::GeneralRequest(_) => id::GENERAL_REQUEST,
            Message::DeviceData(_) => id::DEVICE_DATA,
            Message::Transducer(_) => id::TRANSDUCER,
        }
    }

    /// Length of its payload.
    pub fn payload_len(&self) -> usize {
        match self {
            Message::Ack(_) => AckRepr::LEN,
            Message::Nack(n) => n.payload_len(),
            Message::ProtocolVersion(_) => ProtocolVersionRepr::LEN,
            Message::GeneralRequest(_) => GeneralRequestRepr::LEN,
            Message::DeviceData(d) => d.payload_len(),
            Message::Transducer(_) => TRANSDUCER_LEN,
        }
    }

    /// Writes its payload into `out`; returns the length written.
    pub fn emit(&self, out: &mut [u8]) -> Result<usize, Error> {
        match self {
            Message::Ack(m) => m.emit(out),
            Message::Nack(m) => m.emit(out),
            Message::ProtocolVersion(m) => m.emit(out),
            Message::GeneralRequest(m) => m.emit(out),
            Message::DeviceData(m) => m.emit(out),
            Message::Transducer(m) => m.emit(out),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ids_round_trip_and_unknown_ids_are_named() {
        let msgs = [
            Message::Ack(AckRepr { acked_id: 6 }),
            Message::Nack(NackRepr {
                nacked_id: 6,
                text: b"no",
            }),
            Message::ProtocolVersion(ProtocolVersionRepr {
                major: 1,
                minor: 2,
                patch: 3,
            }),
            Message::GeneralRequest(GeneralRequestRepr { requested_id: 5 }),
        ];
        for m in msgs {
            let mut buf = [0u8; 16];
            let n = m.emit(&mut buf).unwrap();
            assert_eq!(n, m.payload_len());
            assert_eq!(Message::parse(m.message_id(), &buf[..n]), Ok(m));
        }
        assert_eq!(Message::parse(4, &[0; 6]), Err(Error::UnknownId(4)));
    }
}
