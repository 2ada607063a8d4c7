//! The method identifiers shared by every backend, the CLI and the metrics files (design.md).

use core::fmt;
use core::str::FromStr;

use crate::interpolated_distance::DistanceMode;

/// Which back surface the back-face pass keeps (Wyman 2005a §3.2).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum BackSurface {
    /// The furthest surface: largest depth (depth test Greater, cleared to 0). The default.
    #[default]
    Furthest,
    /// The second surface: the nearest back-facing one (depth test Less).
    Second,
}

/// An image-space refraction method of Wyman 2005a.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Method {
    /// `single`: one interface (Table 1 "1-sided").
    Single,
    /// `wyman` (`Interpolated`), `wyman-dv` (`ViewOnly`), `wyman-dn` (`NormalOnly`): two
    /// interfaces with the given distance approximation and back surface.
    TwoInterface {
        /// How `d~` is approximated.
        distance: DistanceMode,
        /// Which back surface is rasterised.
        back: BackSurface,
    },
}

impl Method {
    /// Every method with its default back surface, in report order.
    pub const ALL: [Method; 4] = [
        Method::Single,
        Method::TwoInterface {
            distance: DistanceMode::Interpolated,
            back: BackSurface::Furthest,
        },
        Method::TwoInterface {
            distance: DistanceMode::ViewOnly,
            back: BackSurface::Furthest,
        },
        Method::TwoInterface {
            distance: DistanceMode::NormalOnly,
            back: BackSurface::Furthest,
        },
    ];

    /// The method id of design.md (`single`, `wyman`, `wyman-dv`, `wyman-dn`); the back surface
    /// is not part of the id.
    pub fn id(&self) -> &'static str {
        match self {
            Method::Single => "single",
            Method::TwoInterface {
                distance: DistanceMode::Interpolated,
                ..
            } => "wyman",
            Method::TwoInterface {
                distance: DistanceMode::ViewOnly,
                ..
            } => "wyman-dv",
            Method::TwoInterface {
                distance: DistanceMode::NormalOnly,
                ..
            } => "wyman-dn",
        }
    }

    /// The distance approximation of the kernel (`Interpolated` for `single`, which does not
    /// use one).
    pub fn distance_mode(&self) -> DistanceMode {
        match self {
            Method::Single => DistanceMode::Interpolated,
            Method::TwoInterface { distance, .. } => *distance,
        }
    }

    /// The same method with another back surface (no effect on `single`).
    pub fn with_back_surface(self, back: BackSurface) -> Self {
        match self {
            Method::Single => Method::Single,
            Method::TwoInterface { distance, .. } => Method::TwoInterface { distance, back },
        }
    }
}

impl fmt::Display for Method {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.id())
    }
}

/// An unknown method id.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct UnknownMethod(pub String);

impl fmt::Display for UnknownMethod {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "unknown method `{}`; expected one of: single, wyman, wyman-dv, wyman-dn",
            self.0
        )
    }
}

impl std::error::Error for UnknownMethod {}

impl FromStr for Method {
    type Err = UnknownMethod;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Method::ALL
            .into_iter()
            .find(|m| m.id() == s)
            .ok_or_else(|| UnknownMethod(s.to_owned()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ids_round_trip() {
        for m in Method::ALL {
            assert_eq!(m.id().parse::<Method>(), Ok(m));
        }
        assert!("wyman-xx".parse::<Method>().is_err());
    }
}
