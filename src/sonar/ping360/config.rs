//! What the Ping360 driver asks of the sonar, and how the sonar sits on the vehicle.

use crate::link::ping::ping360::{
    PingSettings, GRADIANS, SAMPLES_RANGE, SAMPLE_PERIOD_RANGE, TRANSMIT_DURATION_RANGE,
    TRANSMIT_FREQUENCY_RANGE,
};
use crate::math::{PI, TAU};
use crate::sonar::{MAX_RANGE_M, MAX_STEP_RAD, MIN_RANGE_M, MIN_STEP_RAD};

/// Radians per gradian.
pub const RAD_PER_GRAD: f32 = TAU / GRADIANS as f32;
/// Largest head step, gradians: the most the sonar module's scanlines allow (0.2 rad).
pub const MAX_STEP_GRAD: u16 = 12;

/// The driver's settings. [`Default`]: a full circle in 2-gradian (1.8°) steps, 30 m over 600
/// samples at 1500 m/s, normal gain, 750 kHz, a 100 µs pulse, 0.5 s timeout, mounted as
/// described at [`Ping360Config::zero_bearing_rad`].
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Ping360Config {
    /// Head angle where the sector starts, gradians, `0 ..= 399`.
    pub start_grad: u16,
    /// Sector width, gradians, `2·step_grad ..= 400`. 400: continuous rotation; less: the head
    /// goes back and forth from `start_grad` to `start_grad + width_grad`.
    pub width_grad: u16,
    /// Head step between pings, gradians, `1 ..= MAX_STEP_GRAD` (1 gradian = 0.9°).
    pub step_grad: u16,
    /// `gain_setting`: 0 low, 1 normal, 2 high.
    pub gain: u8,
    /// `transmit_duration`, µs, `1 ..= 1000`: longer pulses reach farther, at the cost of range
    /// resolution.
    pub transmit_duration_us: u16,
    /// `sample_period`, × 25 ns, `80 ..= 40000` ([`Ping360Config::sample_period_for`] gives it
    /// for a range).
    pub sample_period: u16,
    /// `number_of_samples`, `200 ..= 1200`.
    pub samples: u16,
    /// `transmit_frequency`, kHz, `500 ..= 1000` (650–850 work best, says Blue Robotics).
    pub frequency_khz: u16,
    /// Speed of sound, m/s, `1300 ..= 1800` (1500: sea water; ≈ 1480 fresh water at 20 °C).
    pub sound_speed: f32,
    /// Bearing of the head's angle 0 from the bow, radians counter-clockwise, `±2π`. Default π:
    /// angle 200 looks forward, as Ping Viewer's forward sector and the sample recording
    /// (150–250) have it with the sonar upright and its cable aft. Check on your vehicle.
    pub zero_bearing_rad: f32,
    /// The head angle grows clockwise seen from above (default, the sonar upright); `false`
    /// for a sonar mounted upside down.
    pub clockwise: bool,
    /// A `transducer` not answered by its `device_data` within this long is counted as a
    /// timeout and the head steps on, ms, `100 ..= 10000`. A ping of 1200 samples at 50 m
    /// takes about 0.2 s at 115 200 baud (67 ms listening, 106 ms of data, a step of the
    /// motor); Blue Robotics advises 4 s for the worst case, a long move (the first command,
    /// from wherever the head is, may time out once: counted, and its late answer is still
    /// used). Each lost answer costs this long of sonar time, and a sweep slowed by many lets
    /// the vehicle outrun what its sonar has seen (see the README's "With a Ping360").
    pub timeout_ms: u32,
}

impl Default for Ping360Config {
    fn default() -> Self {
        Ping360Config {
            start_grad: 0,
            width_grad: GRADIANS,
            step_grad: 2,
            gain: 1,
            transmit_duration_us: 100,
            sample_period: 2667,
            samples: 600,
            frequency_khz: 750,
            sound_speed: 1500.0,
            zero_bearing_rad: PI,
            clockwise: true,
            timeout_ms: 500,
        }
    }
}

/// A [`Ping360Config`] field out of its range (the field's name).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ConfigError(pub &'static str);

impl core::fmt::Display for ConfigError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(f, "Ping360 setting `{}` out of range", self.0)
    }
}

impl core::error::Error for ConfigError {}

impl Ping360Config {
    /// What the board images drive (they take no command line): the whole circle in 2-gradian
    /// steps, 30 m over 300 samples (10 cm a sample; a 324-byte `device_data`, 73 ms a ping at
    /// 115 200 baud: 5 ms of head step, 40 ms listening, 28 ms on the line), the defaults'
    /// gain, pulse, frequency and mounting, and a timeout of four pings' time (293 ms), the
    /// HIL's rule for a scenario's Ping360 (`hil/src/ping360/sim.rs`), so a lockstep run on
    /// QEMU and one of the host-process firmware with the same settings fly the same. Change it
    /// here for your sonar and range, and rebuild.
    pub const BOARD: Ping360Config = Ping360Config {
        start_grad: 0,
        width_grad: GRADIANS,
        step_grad: 2,
        gain: 1,
        transmit_duration_us: 100,
        sample_period: 5333,
        samples: 300,
        frequency_khz: 750,
        sound_speed: 1500.0,
        zero_bearing_rad: PI,
        clockwise: true,
        timeout_ms: 293,
    };

    /// Checks every field; also that the range the settings give is one the sonar module takes
    /// (`0.5 ..= 200` m).
    pub fn validate(&self) -> Result<(), ConfigError> {
        let fail = |name| Err(ConfigError(name));
        if self.start_grad >= GRADIANS {
            return fail("start_grad");
        }
        if !(1..=MAX_STEP_GRAD).contains(&self.step_grad) {
            return fail("step_grad");
        }
        if !(self.step_grad.saturating_mul(2)..=GRADIANS).contains(&self.width_grad) {
            return fail("width_grad");
        }
        if self.gain > 2 {
            return fail("gain");
        }
        if !TRANSMIT_DURATION_RANGE.contains(&self.transmit_duration_us) {
            return fail("transmit_duration_us");
        }
        if !SAMPLE_PERIOD_RANGE.contains(&self.sample_period) {
            return fail("sample_period");
        }
        if !SAMPLES_RANGE.contains(&self.samples) {
            return fail("samples");
        }
        if !TRANSMIT_FREQUENCY_RANGE.contains(&self.frequency_khz) {
            return fail("frequency_khz");
        }
        if !(1300.0..=1800.0).contains(&self.sound_speed) {
            return fail("sound_speed");
        }
        if !(self.zero_bearing_rad.is_finite() && self.zero_bearing_rad.abs() <= TAU) {
            return fail("zero_bearing_rad");
        }
        if !(100..=10_000).contains(&self.timeout_ms) {
            return fail("timeout_ms");
        }
        let range = self.range_m();
        if !(MIN_RANGE_M..=MAX_RANGE_M).contains(&range) {
            return fail("sample_period");
        }
        let step = self.step_rad();
        if !(MIN_STEP_RAD..=MAX_STEP_RAD).contains(&step) {
            return fail("step_grad");
        }
        Ok(())
    }

    /// The range the settings reach, m: `samples × sample_period × 25 ns × c / 2`.
    pub fn range_m(&self) -> f32 {
        f32::from(self.samples) * f32::from(self.sample_period) * 25e-9 * self.sound_speed * 0.5
    }

    /// The head step, rad.
    pub fn step_rad(&self) -> f32 {
        f32::from(self.step_grad) * RAD_PER_GRAD
    }

    /// The `sample_period` that makes `samples` samples reach `range_m` at `sound_speed`:
    /// `2·R / (c · 25 ns · n)`, rounded; `None` outside the definition's `80 ..= 40000`.
    pub fn sample_period_for(range_m: f32, samples: u16, sound_speed: f32) -> Option<u16> {
        let p = 2.0 * range_m / (sound_speed * 25e-9 * f32::from(samples.max(1)));
        let p = libm::roundf(p);
        (80.0..=40_000.0)
            .contains(&p)
            .then_some(p as u16)
            .filter(|p| SAMPLE_PERIOD_RANGE.contains(p))
    }

    /// The `transducer` settings to ping at head angle `angle`.
    pub fn settings(&self, angle: u16) -> PingSettings {
        PingSettings {
            mode: 1,
            gain_setting: self.gain,
            angle,
            transmit_duration: self.transmit_duration_us,
            sample_period: self.sample_period,
            transmit_frequency: self.frequency_khz,
            number_of_samples: self.samples,
        }
    }

    /// The bow-relative bearing (counter-clockwise, rad, wrapped to ±π) of head angle
    /// `angle` gradians.
    pub fn bearing_rad(&self, angle: u16) -> f32 {
        let a = f32::from(angle) * RAD_PER_GRAD;
        let signed = if self.clockwise { -a } else { a };
        crate::math::wrap_angle(self.zero_bearing_rad + signed)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_default_is_valid_and_reaches_30_m() {
        let c = Ping360Config::default();
        assert_eq!(c.validate(), Ok(()));
        assert!((c.range_m() - 30.0).abs() < 0.01, "{}", c.range_m());
        assert_eq!(
            Ping360Config::sample_period_for(30.0, 600, 1500.0),
            Some(2667)
        );
        // The recording's settings: 1200 samples of 90 × 25 ns at 1500 m/s = 2.025 m.
        let rec = Ping360Config {
            samples: 1200,
            sample_period: 90,
            ..c
        };
        assert!((rec.range_m() - 2.025).abs() < 1e-4);
        assert_eq!(Ping360Config::sample_period_for(0.1, 200, 1500.0), None);
        assert_eq!(
            Ping360Config::sample_period_for(f32::NAN, 200, 1500.0),
            None
        );
    }

    #[test]
    fn the_boards_settings_are_valid_and_reach_30_m_over_300_samples() {
        let b = Ping360Config::BOARD;
        assert_eq!(b.validate(), Ok(()));
        assert_eq!(
            Ping360Config::sample_period_for(30.0, 300, 1500.0),
            Some(b.sample_period)
        );
        assert!((b.range_m() - 30.0).abs() < 0.01, "{}", b.range_m());
    }

    #[test]
    fn bearings_follow_the_mounting() {
        let c = Ping360Config::default();
        // Angle 0 astern, 200 ahead; clockwise seen from above, so 250 is 45° to starboard,
        // 300 abeam to starboard and 100 abeam to port.
        assert!(c.bearing_rad(200).abs() < 1e-6);
        assert!((c.bearing_rad(250) + PI / 4.0).abs() < 1e-5);
        assert!((c.bearing_rad(300) + PI / 2.0).abs() < 1e-5);
        assert!((c.bearing_rad(100) - PI / 2.0).abs() < 1e-5);
        let flipped = Ping360Config {
            clockwise: false,
            zero_bearing_rad: 0.0,
            ..c
        };
        assert!((flipped.bearing_rad(100) - PI / 2.0).abs() < 1e-5);
        assert!((flipped.bearing_rad(300) + PI / 2.0).abs() < 1e-5);
    }

    #[test]
    fn refusals_name_the_field() {
        let c = Ping360Config::default();
        let cases: [(Ping360Config, &str); 8] = [
            (
                Ping360Config {
                    start_grad: 400,
                    ..c
                },
                "start_grad",
            ),
            (Ping360Config { step_grad: 13, ..c }, "step_grad"),
            (Ping360Config { width_grad: 3, ..c }, "width_grad"),
            (Ping360Config { gain: 3, ..c }, "gain"),
            (Ping360Config { samples: 100, ..c }, "samples"),
            (
                Ping360Config {
                    sound_speed: f32::NAN,
                    ..c
                },
                "sound_speed",
            ),
            (
                // 200 samples of 80 × 25 ns: 0.3 m, under the scanline minimum.
                Ping360Config {
                    samples: 200,
                    sample_period: 80,
                    ..c
                },
                "sample_period",
            ),
            (
                Ping360Config {
                    timeout_ms: 50,
                    ..c
                },
                "timeout_ms",
            ),
        ];
        for (cfg, name) in cases {
            assert_eq!(cfg.validate(), Err(ConfigError(name)));
        }
    }
}
