//! The Ping360's messages: `device_data` (2300) and `transducer` (2601).
//!
//! Both begin with the same twelve bytes of ping settings ([`PingSettings`], Blue Robotics'
//! definition calls the fields the same names):
//!
//! | offset | field | type | unit, range in the definition |
//! |---|---|---|---|
//! | 0 | `mode` | u8 | "1 for Ping360" (a real Ping360 answers 0; not checked) |
//! | 1 | `gain_setting` | u8 | 0 low, 1 normal, 2 high |
//! | 2 | `angle` | u16 | gradians, 0 ..= 399 |
//! | 4 | `transmit_duration` | u16 | µs, 1 ..= 1000 |
//! | 6 | `sample_period` | u16 | × 25 ns, 80 ..= 40 000 (2 ..= 1000 µs) |
//! | 8 | `transmit_frequency` | u16 | kHz, 500 ..= 1000 |
//! | 10 | `number_of_samples` | u16 | 200 ..= 1200 |
//!
//! `device_data` then carries `data`: a u16 length and that many u8 samples, nearest first.
//! `transducer` carries `transmit` u8 (1: ping once the head is at `angle`, 0: only move) and a
//! reserved u8. The sonar answers a `transducer` with a `device_data`.
//!
//! What is checked: everything, when emitting a `transducer` (it commands a device); when
//! parsing a `device_data`, the fields a receiver computes with (`angle`, `sample_period`,
//! `gain_setting`) and the data length against the payload length. The other fields of a
//! received `device_data` are reported as sent (a real Ping360 answers `mode` 0, for one).

use super::{get_u16, put_u16, Error};

/// Gradians in a full turn: the Ping360's `angle` is `0 ..= 399`.
pub const GRADIANS: u16 = 400;
/// Payload bytes of `device_data` before the samples: the settings and the data length.
pub const DEVICE_DATA_HEAD_LEN: usize = PingSettings::LEN + 2;
/// Payload length of `transducer`.
pub const TRANSDUCER_LEN: usize = PingSettings::LEN + 2;
/// Shortest and longest `sample_period` the definition allows, × 25 ns.
pub const SAMPLE_PERIOD_RANGE: core::ops::RangeInclusive<u16> = 80..=40_000;
/// `transmit_duration` range, µs.
pub const TRANSMIT_DURATION_RANGE: core::ops::RangeInclusive<u16> = 1..=1000;
/// `transmit_frequency` range, kHz.
pub const TRANSMIT_FREQUENCY_RANGE: core::ops::RangeInclusive<u16> = 500..=1000;
/// `number_of_samples` range.
pub const SAMPLES_RANGE: core::ops::RangeInclusive<u16> = 200..=1200;

/// The settings of one ping, shared by `transducer` and `device_data`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct PingSettings {
    /// `mode`.
    pub mode: u8,
    /// `gain_setting`: 0 low, 1 normal, 2 high.
    pub gain_setting: u8,
    /// `angle`: head angle, gradians, `0 ..= 399`.
    pub angle: u16,
    /// `transmit_duration`, µs.
    pub transmit_duration: u16,
    /// `sample_period`, × 25 ns.
    pub sample_period: u16,
    /// `transmit_frequency`, kHz.
    pub transmit_frequency: u16,
    /// `number_of_samples`.
    pub number_of_samples: u16,
}

impl PingSettings {
    /// Length on the wire.
    pub const LEN: usize = 12;

    fn parse(p: &[u8]) -> Result<Self, Error> {
        let u16_at = |at| get_u16(p, at).ok_or(Error::Length);
        Ok(PingSettings {
            mode: *p.first().ok_or(Error::Length)?,
            gain_setting: *p.get(1).ok_or(Error::Length)?,
            angle: u16_at(2)?,
            transmit_duration: u16_at(4)?,
            sample_period: u16_at(6)?,
            transmit_frequency: u16_at(8)?,
            number_of_samples: u16_at(10)?,
        })
    }

    fn emit(&self, out: &mut [u8]) -> Result<(), Error> {
        let dst = out.get_mut(..Self::LEN).ok_or(Error::BufferTooSmall)?;
        if let Some([m, g]) = dst.get_mut(..2) {
            *m = self.mode;
            *g = self.gain_setting;
        }
        for (at, v) in [
            (2, self.angle),
            (4, self.transmit_duration),
            (6, self.sample_period),
            (8, self.transmit_frequency),
            (10, self.number_of_samples),
        ] {
            put_u16(dst, at, v);
        }
        Ok(())
    }

    /// The checks a receiver relies on: `angle`, `gain_setting`, `sample_period`.
    fn check_received(&self) -> Result<(), Error> {
        if self.angle >= GRADIANS {
            return Err(Error::Field("angle"));
        }
        if self.gain_setting > 2 {
            return Err(Error::Field("gain_setting"));
        }
        if !SAMPLE_PERIOD_RANGE.contains(&self.sample_period) {
            return Err(Error::Field("sample_period"));
        }
        Ok(())
    }

    /// Every field within the definition's range (what a command must meet).
    pub fn check(&self) -> Result<(), Error> {
        self.check_received()?;
        if !TRANSMIT_DURATION_RANGE.contains(&self.transmit_duration) {
            return Err(Error::Field("transmit_duration"));
        }
        if !TRANSMIT_FREQUENCY_RANGE.contains(&self.transmit_frequency) {
            return Err(Error::Field("transmit_frequency"));
        }
        if !SAMPLES_RANGE.contains(&self.number_of_samples) {
            return Err(Error::Field("number_of_samples"));
        }
        Ok(())
    }

    /// Range of one sample, m: `sample_period × 25 ns × c / 2` (the echo's round trip), for a
    /// speed of sound `sound_speed` m/s.
    pub fn sample_m(&self, sound_speed: f32) -> f32 {
        f32::from(self.sample_period) * 25e-9 * sound_speed * 0.5
    }
}

/// The part of a `device_data` before its samples: what a stream decoder knows once 14 bytes of
/// the payload are in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct DeviceDataHead {
    /// The ping's settings.
    pub settings: PingSettings,
    /// Samples that follow.
    pub data_len: u16,
}

impl DeviceDataHead {
    /// Parses the first [`DEVICE_DATA_HEAD_LEN`] bytes of a `device_data` payload whose whole
    /// length is `payload_len`: the data length must be the rest of the payload.
    pub fn parse(head: &[u8], payload_len: usize) -> Result<Self, Error> {
        let settings = PingSettings::parse(head)?;
        let data_len = get_u16(head, PingSettings::LEN).ok_or(Error::Length)?;
        if payload_len != DEVICE_DATA_HEAD_LEN + usize::from(data_len) {
            return Err(Error::Length);
        }
        settings.check_received()?;
        Ok(DeviceDataHead { settings, data_len })
    }
}

/// `device_data` (2300): the settings of one ping and its samples.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct DeviceDataRepr<'a> {
    /// The settings the ping was taken with.
    pub settings: PingSettings,
    /// Echo intensities, nearest first (empty after a `transducer` with `transmit` 0).
    pub data: &'a [u8],
}

impl<'a> DeviceDataRepr<'a> {
    /// Parses a whole payload.
    pub fn parse(payload: &'a [u8]) -> Result<Self, Error> {
        let head = DeviceDataHead::parse(payload, payload.len())?;
        Ok(DeviceDataRepr {
            settings: head.settings,
            data: payload.get(DEVICE_DATA_HEAD_LEN..).unwrap_or(&[]),
        })
    }

    /// Payload length.
    pub fn payload_len(&self) -> usize {
        DEVICE_DATA_HEAD_LEN + self.data.len()
    }

    /// Writes the payload; returns its length. Refuses what [`Self::parse`] would refuse, and
    /// more than `u16::MAX` samples.
    pub fn emit(&self, out: &mut [u8]) -> Result<usize, Error> {
        self.settings.check_received()?;
        let n = u16::try_from(self.data.len()).map_err(|_| Error::Length)?;
        let len = self.payload_len();
        let dst = out.get_mut(..len).ok_or(Error::BufferTooSmall)?;
        self.settings.emit(dst)?;
        put_u16(dst, PingSettings::LEN, n);
        if let Some(d) = dst.get_mut(DEVICE_DATA_HEAD_LEN..) {
            d.copy_from_slice(self.data);
        }
        Ok(len)
    }
}

/// `transducer` (2601): move the head to `angle` and, if `transmit`, ping with these settings.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct TransducerRepr {
    /// The settings to ping with.
    pub settings: PingSettings,
    /// Ping once the head is there (`transmit` 1), or only move it (0).
    pub transmit: bool,
}

impl TransducerRepr {
    /// Parses a payload of exactly [`TRANSDUCER_LEN`] bytes; every setting must be within the
    /// definition's range and `transmit` 0 or 1.
    pub fn parse(payload: &[u8]) -> Result<Self, Error> {
        if payload.len() != TRANSDUCER_LEN {
            return Err(Error::Length);
        }
        let settings = PingSettings::parse(payload)?;
        settings.check()?;
        let transmit = match payload.get(PingSettings::LEN) {
            Some(0) => false,
            Some(1) => true,
            _ => return Err(Error::Field("transmit")),
        };
        Ok(TransducerRepr { settings, transmit })
    }

    /// Writes the payload (reserved byte 0); returns its length.
    pub fn emit(&self, out: &mut [u8]) -> Result<usize, Error> {
        self.settings.check()?;
        let dst = out.get_mut(..TRANSDUCER_LEN).ok_or(Error::BufferTooSmall)?;
        self.settings.emit(dst)?;
        if let Some([t, reserved]) = dst.get_mut(PingSettings::LEN..) {
            *t = u8::from(self.transmit);
            *reserved = 0;
        }
        Ok(TRANSDUCER_LEN)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn settings() -> PingSettings {
        PingSettings {
            mode: 1,
            gain_setting: 0,
            angle: 150,
            transmit_duration: 16,
            sample_period: 90,
            transmit_frequency: 1000,
            number_of_samples: 4,
        }
    }

    /// A `device_data` payload as a real Ping360 sends it (the fields of the recording in
    /// `shared/data/ping360/`, first message, with 4 samples instead of 1200).
    const DEVICE_DATA: [u8; 18] = [
        0x00, // mode 0, as the real sonar answers
        0x00, // gain_setting 0
        0x96, 0x00, // angle 150
        0x10, 0x00, // transmit_duration 16 µs
        0x5A, 0x00, // sample_period 90 × 25 ns
        0xE8, 0x03, // transmit_frequency 1000 kHz
        0xB0, 0x04, // number_of_samples 1200
        0x04, 0x00, // data length 4
        0x4c, 0x98, 0xc9, 0xe4, // the first four samples
    ];

    #[test]
    fn device_data_bytes() {
        let d = DeviceDataRepr::parse(&DEVICE_DATA).unwrap();
        assert_eq!(
            d.settings,
            PingSettings {
                mode: 0,
                number_of_samples: 1200,
                ..settings()
            }
        );
        assert_eq!(d.data, &[0x4c, 0x98, 0xc9, 0xe4]);
        let mut out = [0u8; 18];
        assert_eq!(d.emit(&mut out), Ok(18));
        assert_eq!(out, DEVICE_DATA);
        // 90 × 25 ns × 1500 m/s / 2 = 1.6875 mm per sample.
        assert!((d.settings.sample_m(1500.0) - 1.6875e-3).abs() < 1e-9);
    }

    #[test]
    fn device_data_refusals() {
        // The data length must be the rest of the payload.
        assert_eq!(
            DeviceDataRepr::parse(&DEVICE_DATA[..17]),
            Err(Error::Length)
        );
        assert_eq!(DeviceDataRepr::parse(&DEVICE_DATA[..5]), Err(Error::Length));
        let mut bad = DEVICE_DATA;
        bad[2] = 0x90;
        bad[3] = 0x01; // angle 400
        assert_eq!(DeviceDataRepr::parse(&bad), Err(Error::Field("angle")));
        let mut bad = DEVICE_DATA;
        bad[6] = 79; // sample_period 79
        assert_eq!(
            DeviceDataRepr::parse(&bad),
            Err(Error::Field("sample_period"))
        );
        let mut bad = DEVICE_DATA;
        bad[1] = 3;
        assert_eq!(
            DeviceDataRepr::parse(&bad),
            Err(Error::Field("gain_setting"))
        );
        // An empty data vector (a `transducer` with transmit 0) is valid.
        let mut empty = [0u8; 14];
        empty.copy_from_slice(&DEVICE_DATA[..14]);
        empty[12] = 0;
        assert_eq!(DeviceDataRepr::parse(&empty).unwrap().data, &[] as &[u8]);
    }

    /// A `transducer` payload: ping at 200 gradians, normal gain, 20 m at 1500 m/s with 1200
    /// samples (sample period 889), 1000 kHz, 80 µs.
    const TRANSDUCER: [u8; 14] = [
        0x01, 0x01, // mode 1, gain 1
        0xC8, 0x00, // angle 200
        0x50, 0x00, // transmit_duration 80
        0x79, 0x03, // sample_period 889
        0xE8, 0x03, // transmit_frequency 1000
        0xB0, 0x04, // number_of_samples 1200
        0x01, 0x00, // transmit, reserved
    ];

    #[test]
    fn transducer_bytes_and_refusals() {
        let t = TransducerRepr {
            settings: PingSettings {
                mode: 1,
                gain_setting: 1,
                angle: 200,
                transmit_duration: 80,
                sample_period: 889,
                transmit_frequency: 1000,
                number_of_samples: 1200,
            },
            transmit: true,
        };
        let mut out = [0u8; 14];
        assert_eq!(t.emit(&mut out), Ok(14));
        assert_eq!(out, TRANSDUCER);
        assert_eq!(TransducerRepr::parse(&TRANSDUCER), Ok(t));
        let mut bad = TRANSDUCER;
        bad[12] = 2;
        assert_eq!(TransducerRepr::parse(&bad), Err(Error::Field("transmit")));
        assert_eq!(TransducerRepr::parse(&TRANSDUCER[..13]), Err(Error::Length));
        for (field, s) in [
            (
                "transmit_frequency",
                PingSettings {
                    transmit_frequency: 499,
                    ..t.settings
                },
            ),
            (
                "transmit_duration",
                PingSettings {
                    transmit_duration: 0,
                    ..t.settings
                },
            ),
            (
                "number_of_samples",
                PingSettings {
                    number_of_samples: 1201,
                    ..t.settings
                },
            ),
            (
                "angle",
                PingSettings {
                    angle: 400,
                    ..t.settings
                },
            ),
        ] {
            let t = TransducerRepr {
                settings: s,
                transmit: true,
            };
            assert_eq!(t.emit(&mut out), Err(Error::Field(field)));
        }
        assert_eq!(t.emit(&mut out[..13]), Err(Error::BufferTooSmall));
    }
}
