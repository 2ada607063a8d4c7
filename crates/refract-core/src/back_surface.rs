//! Which back surface the back-face pass keeps (Wyman 2005a §3.2).

/// Which back surface the back-face pass keeps (Wyman 2005a §3.2).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum BackSurface {
    /// The furthest surface: largest depth (depth test Greater, cleared to 0). The default.
    #[default]
    Furthest,
    /// The second surface: the nearest back-facing one (depth test Less).
    Second,
}
