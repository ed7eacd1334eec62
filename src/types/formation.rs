//! A formation request (seed 001 §3.2): the lattice a vehicle keeps with the others. The
//! lattice's geometry — nodes, the virtual leader — is the planner's (`crate::planner::formation`).

/// A formation slot request: the lattice this vehicle keeps with the others.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Formation {
    /// q, the formation descriptor (001 §3.2): nodes per agent, 3 (the honeycomb: hexagonal
    /// cells), 4 (the square lattice) or 6 (the triangular lattice).
    pub q: u8,
    /// λ, the lattice length: the ideal distance between neighbours, m. 0.5 ..= 1000.
    pub lattice_m: f32,
    /// θ₀, orientation of the lattice's first node direction from +x, rad.
    pub orientation: f32,
    /// A⁻ of the virtual leader's goal-point PDF. 0.001 ..= 10⁴.
    pub attraction: f32,
}

/// Why a formation request was refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum FormationError {
    /// q is not 3, 4 or 6.
    Descriptor,
    /// A number is NaN or infinite.
    NonFinite,
    /// λ or the attraction is out of range.
    OutOfRange,
}

impl core::fmt::Display for FormationError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            FormationError::Descriptor => "formation descriptor q must be 3, 4 or 6",
            FormationError::NonFinite => "formation has a non-finite number",
            FormationError::OutOfRange => "formation lattice or attraction out of range",
        })
    }
}

impl core::error::Error for FormationError {}

impl Formation {
    /// Checks q, λ, θ₀ and A⁻.
    pub fn validate(&self) -> Result<(), FormationError> {
        if !matches!(self.q, 3 | 4 | 6) {
            return Err(FormationError::Descriptor);
        }
        let nums = [self.lattice_m, self.orientation, self.attraction];
        if nums.iter().any(|v| !v.is_finite()) {
            return Err(FormationError::NonFinite);
        }
        if !(0.5..=1000.0).contains(&self.lattice_m) || !(0.001..=1e4).contains(&self.attraction) {
            return Err(FormationError::OutOfRange);
        }
        Ok(())
    }
}
