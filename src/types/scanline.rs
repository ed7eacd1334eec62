//! One ping of a mechanically scanned imaging sonar, as the link carries it and the sonar
//! module reads it.

/// Most bins a scanline may have (the Micron's maximum resolution).
pub const MAX_BINS: usize = 512;
/// Shortest accepted scanline range, m.
pub const MIN_RANGE_M: f32 = 0.5;
/// Longest accepted scanline range, m.
pub const MAX_RANGE_M: f32 = 200.0;
/// Smallest accepted head step magnitude, rad (0.057°; the Micron's finest is 0.45°).
pub const MIN_STEP_RAD: f32 = 1.0e-3;
/// Largest accepted head step magnitude, rad (11.5°; the Micron's coarsest is 3.6°).
pub const MAX_STEP_RAD: f32 = 0.2;

/// One ping of the sonar head: intensities along one bearing.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Scanline<'a> {
    /// Ping time, ms since boot.
    pub time_ms: u64,
    /// Head angle relative to the bow, counter-clockwise positive, rad (any finite value; it is
    /// wrapped).
    pub bearing_rad: f32,
    /// Head step between pings, rad; only its magnitude is used (the sweep direction is read
    /// from successive bearings). [`MIN_STEP_RAD`] ..= [`MAX_STEP_RAD`].
    pub step_rad: f32,
    /// Range of the last bin's far edge, m ([`MIN_RANGE_M`] ..= [`MAX_RANGE_M`]).
    pub range_m: f32,
    /// Intensities, nearest first, 1 ..= [`MAX_BINS`] of them.
    pub bins: &'a [u8],
}

/// Why a scanline (or its pose) was refused. Refused scanlines change no state except
/// [`Counters::rejected`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ScanError {
    /// Bearing, step or range is NaN or infinite.
    NonFinite,
    /// Range outside [`MIN_RANGE_M`] ..= [`MAX_RANGE_M`].
    RangeOutOfRange,
    /// Step magnitude outside [`MIN_STEP_RAD`] ..= [`MAX_STEP_RAD`].
    StepOutOfRange,
    /// The scanline has no bins.
    NoBins,
    /// More than [`MAX_BINS`] bins.
    TooManyBins,
    /// The pose is non-finite or farther than [`MAX_POSITION_M`] from the origin.
    BadPose,
}

impl core::fmt::Display for ScanError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            ScanError::NonFinite => "scanline has a non-finite bearing, step or range",
            ScanError::RangeOutOfRange => "scanline range out of 0.5 ..= 200 m",
            ScanError::StepOutOfRange => "scanline step out of 0.001 ..= 0.2 rad",
            ScanError::NoBins => "scanline has no bins",
            ScanError::TooManyBins => "scanline has more than 512 bins",
            ScanError::BadPose => "pose is non-finite or beyond 100 km",
        })
    }
}

impl core::error::Error for ScanError {}

impl Scanline<'_> {
    /// Checks the scanline's numbers and bin count.
    pub fn validate(&self) -> Result<(), ScanError> {
        if !(self.bearing_rad.is_finite() && self.step_rad.is_finite() && self.range_m.is_finite())
        {
            return Err(ScanError::NonFinite);
        }
        if !(MIN_RANGE_M..=MAX_RANGE_M).contains(&self.range_m) {
            return Err(ScanError::RangeOutOfRange);
        }
        if !(MIN_STEP_RAD..=MAX_STEP_RAD).contains(&self.step_rad.abs()) {
            return Err(ScanError::StepOutOfRange);
        }
        if self.bins.is_empty() {
            return Err(ScanError::NoBins);
        }
        if self.bins.len() > MAX_BINS {
            return Err(ScanError::TooManyBins);
        }
        Ok(())
    }

    /// Bin spacing Δ, m (positive for a valid scanline).
    pub fn bin_m(&self) -> f32 {
        self.range_m / (self.bins.len().max(1) as f32)
    }
}
