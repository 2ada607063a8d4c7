//! The parameter every approximate family but the engines' shares: how many wavelengths a
//! frame of a dispersive scene traces through the method's kernel
//! ([`refract_core::spectral::WavelengthBins`]; the engine family disperses as each engine
//! does, or not at all).

use refract_core::spectral::{MAX_WAVELENGTH_BINS, WavelengthBins};

use super::{ParamKind, ParamSpec, ParamValue};

/// The wavelengths a method traces through a dispersive refractor: 1 is the d line only
/// (dispersion ignored, one frame), `N` in `2..=`[`MAX_WAVELENGTH_BINS`] is `N` frames at the
/// middles of `N` bins whose colours are summed with the bins' weights. A scene without
/// dispersion is one frame whatever the count.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct DispersionWavelengths(u32);

impl DispersionWavelengths {
    /// Three: blue, green and red light, as engines disperse (three.js, Kakimoto et al.'s
    /// chromatic aberration).
    pub const DEFAULT: Self = Self(3);

    /// `count` wavelengths, or `None` outside `1..=`[`MAX_WAVELENGTH_BINS`].
    pub fn new(count: u32) -> Option<Self> {
        (1..=MAX_WAVELENGTH_BINS as u32)
            .contains(&count)
            .then_some(Self(count))
    }

    /// The count.
    pub fn count(self) -> u32 {
        self.0
    }

    /// The bins traced, `None` for 1 (the d line alone).
    pub fn bins(self) -> Option<WavelengthBins> {
        (self.0 > 1)
            .then(|| WavelengthBins::new(self.0 as usize))
            .flatten()
    }

    /// Sets `wavelengths`.
    pub(super) fn apply(&mut self, name: &str, value: ParamValue) -> bool {
        match (name, value) {
            ("wavelengths", ParamValue::Integer(v)) => Self::new(v).map(|w| *self = w).is_some(),
            _ => false,
        }
    }

    /// `wavelengths`.
    pub(super) fn get(self, name: &str) -> Option<ParamValue> {
        (name == "wavelengths").then_some(ParamValue::Integer(self.0))
    }
}

impl Default for DispersionWavelengths {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// The `wavelengths` parameter's spec, on every row that traces dispersion through its kernel.
pub(super) const WAVELENGTHS_PARAM: ParamSpec = ParamSpec {
    name: "wavelengths",
    doc: "wavelengths traced through a dispersive refractor (Abbe number in the scene), one frame each, colours summed with CIE weights: 1 is the index at the d line only (dispersion ignored), N the middles of N bins of equal probability over 360-830 nm (3: 452, 546, 650 nm)",
    kind: ParamKind::Integer {
        min: 1,
        max: MAX_WAVELENGTH_BINS as u32,
    },
    default: "3",
};
