//! One rendered frame for methods and the reference alike: linear RGB colour plus named AOV
//! layers, with multi-channel EXR output and input and tonemapped PNG output.

use std::collections::BTreeMap;

use glam::Vec3;
use rayon::prelude::*;

use crate::registry::MethodId;
use crate::renderer::RenderError;

/// A per-pixel output beside the colour (an "arbitrary output variable"). Quantities that do not
/// exist at a pixel are NaN (vectors), 0 (counts) or false (flags).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Aov {
    /// The pixel sees the refractor.
    Covered,
    /// Entry point `P1`.
    P1,
    /// Outward shading normal at `P1`.
    N1,
    /// Direction after the first interface, `T1`.
    T1,
    /// Exit point: exact `P2` (reference) or the estimate `P~2` (methods).
    P2,
    /// Outward normal at the exit point.
    N2,
    /// The direction leaving the exit point: for the reference the direction leaving the first
    /// exit `P2` (what image-space methods approximate); for methods their final direction.
    T2,
    /// The direction the reference's path finally leaves the refractor in (the environment
    /// lookup direction; differs from `T2` on paths that leave and re-enter).
    TOut,
    /// Where the escaping ray hit nearby opaque geometry: exact for the reference, the surface
    /// stored in the NG texel used for nearby-geometry methods (Wyman 2005b §4).
    PGeom,
    /// The nearby-geometry texel a method's colour came from: `(x, y)` of the texel in the NG
    /// texture and the object id (`1 + k`) stored there; NaN for a miss.
    NgTexel,
    /// Distance updates of the iterative nearby-geometry lookups (Wyman 2005b §4.3).
    Iterations,
    /// The iterative lookup reached a fixed point (the same texel twice in a row).
    Converged,
    /// Where the exit normal came from, as [`refract_core::gpu::exit_normal_source_code`] (0: none).
    ExitNormalSource,
    /// Interfaces crossed by refraction (TIR bounces not counted).
    Interfaces,
    /// The refractors the path met, as a bit mask: bit `i` for refractor `i` of
    /// `Scene::refractors` (0: none).
    RefractorsMet,
    /// Total internal reflection anywhere on the path.
    Tir,
    /// Total internal reflection at the first exit.
    TirFirstExit,
    /// The distance-map layer of a path's last hit, plus one (0: the last ray left every layer).
    HitLayer,
    /// Linear-search samples of a distance-map path, over all its rays and layers.
    LinearSteps,
    /// Secant steps of a distance-map path.
    SecantSteps,
    /// Secondary rays a distance-map path traced.
    Bounces,
    /// A distance-map ray left every layer, or a `depth-peel` path found no further crossing
    /// while inside a medium (the environment was read instead).
    Miss,
    /// A `pvrr` pixel that was not looked up: its triangle has a vertex whose exact ray ends
    /// outside the map (the zooming region of concave mirrors and convex lenses, Kakimoto et al.
    /// 2007 §4.2, left out as in the paper), is trapped in the lens, or lies past the last
    /// level of the reflection stack.
    Zoom,
    /// An engine method's lookup position fell outside the frame (or behind the eye): the
    /// engine reads the edge texel (clamped) or, Unity HDRP, fades to the environment.
    OffScreen,
}

/// One pixel's value of one AOV layer.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LayerValue {
    /// Of an [`AovKind::Vec3`] layer.
    Vec3(Vec3),
    /// Of an [`AovKind::Count`] layer.
    Count(u32),
    /// Of an [`AovKind::Flag`] layer.
    Flag(bool),
}

/// A family's per-pixel outputs beside the colour, as the frame's layers: what
/// [`Frame::write_row_layers`] writes for the layers of a method's registry row.
pub trait PixelLayers: Sync {
    /// This pixel's value of `aov`, `None` for a layer the family does not compute.
    fn value(&self, aov: Aov) -> Option<LayerValue>;
}

/// The type of an [`Aov`]'s per-pixel values.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AovKind {
    /// A 3-vector (`NAME.X`, `NAME.Y`, `NAME.Z` in EXR).
    Vec3,
    /// A small non-negative integer.
    Count,
    /// A boolean (0/1 in EXR).
    Flag,
}

impl Aov {
    /// Every AOV, in EXR channel order.
    pub const ALL: [Aov; 24] = [
        Aov::Covered,
        Aov::P1,
        Aov::N1,
        Aov::T1,
        Aov::P2,
        Aov::N2,
        Aov::T2,
        Aov::TOut,
        Aov::PGeom,
        Aov::NgTexel,
        Aov::ExitNormalSource,
        Aov::Interfaces,
        Aov::RefractorsMet,
        Aov::Iterations,
        Aov::Tir,
        Aov::TirFirstExit,
        Aov::Converged,
        Aov::HitLayer,
        Aov::LinearSteps,
        Aov::SecantSteps,
        Aov::Bounces,
        Aov::Miss,
        Aov::Zoom,
        Aov::OffScreen,
    ];

    /// The layer name (EXR channel or channel prefix).
    pub const fn name(self) -> &'static str {
        match self {
            Aov::Covered => "covered",
            Aov::P1 => "P1",
            Aov::N1 => "N1",
            Aov::T1 => "T1",
            Aov::P2 => "P2",
            Aov::N2 => "N2",
            Aov::T2 => "T2",
            Aov::TOut => "Tout",
            Aov::PGeom => "Pgeom",
            Aov::NgTexel => "ng_texel",
            Aov::Iterations => "iterations",
            Aov::Converged => "converged",
            Aov::ExitNormalSource => "n2_source",
            Aov::Interfaces => "interfaces",
            Aov::RefractorsMet => "refractors_met",
            Aov::Tir => "tir",
            Aov::TirFirstExit => "tir_first_exit",
            Aov::HitLayer => "hit_layer",
            Aov::LinearSteps => "linear_steps",
            Aov::SecantSteps => "secant_steps",
            Aov::Bounces => "bounces",
            Aov::Miss => "miss",
            Aov::Zoom => "zoom",
            Aov::OffScreen => "off_screen",
        }
    }

    /// The type of its values.
    pub const fn kind(self) -> AovKind {
        match self {
            Aov::P1
            | Aov::N1
            | Aov::T1
            | Aov::P2
            | Aov::N2
            | Aov::T2
            | Aov::TOut
            | Aov::PGeom
            | Aov::NgTexel => AovKind::Vec3,
            Aov::ExitNormalSource
            | Aov::Interfaces
            | Aov::RefractorsMet
            | Aov::Iterations
            | Aov::HitLayer
            | Aov::LinearSteps
            | Aov::SecantSteps
            | Aov::Bounces => AovKind::Count,
            Aov::Covered
            | Aov::Tir
            | Aov::TirFirstExit
            | Aov::Converged
            | Aov::Miss
            | Aov::Zoom
            | Aov::OffScreen => AovKind::Flag,
        }
    }
}

/// The values of one AOV layer, one per pixel, row-major from the top.
#[derive(Clone, Debug, PartialEq)]
pub enum Layer {
    /// Vectors (NaN where absent).
    Vec3(Vec<Vec3>),
    /// Counts or codes (0 where absent).
    Count(Vec<u32>),
    /// Flags (false where absent).
    Flag(Vec<bool>),
}

impl Layer {
    fn empty(kind: AovKind, n: usize) -> Self {
        match kind {
            AovKind::Vec3 => Layer::Vec3(vec![Vec3::NAN; n]),
            AovKind::Count => Layer::Count(vec![0; n]),
            AovKind::Flag => Layer::Flag(vec![false; n]),
        }
    }

    fn len(&self) -> usize {
        match self {
            Layer::Vec3(v) => v.len(),
            Layer::Count(v) => v.len(),
            Layer::Flag(v) => v.len(),
        }
    }
}

/// The largest width or height of a frame any command renders, in pixels: the one bound the
/// CLI (`render`, `compare`, `bench`), sweep files, the experiments library and Python check.
pub const MAX_FRAME_SIZE: u32 = 16384;

/// A rendered frame: linear RGB colour and the AOV layers the renderer wrote.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Frame {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Linear RGB, row-major from the top.
    pub color: Vec<Vec3>,
    layers: BTreeMap<Aov, Layer>,
    /// Rays traced (closest-hit queries; the reference only).
    pub rays: u64,
}

impl Frame {
    /// A black frame without layers.
    pub fn new(width: u32, height: u32) -> Self {
        let mut frame = Self::default();
        frame.reset(width, height);
        frame
    }

    /// Makes this a black `width × height` frame without layers, keeping the colour's memory.
    pub fn reset(&mut self, width: u32, height: u32) {
        self.width = width;
        self.height = height;
        self.color.clear();
        self.color
            .resize((width as usize) * (height as usize), Vec3::ZERO);
        self.layers.clear();
        self.rays = 0;
    }

    /// Makes this a `width × height` frame without layers for a renderer that overwrites every
    /// pixel's colour: the colour's memory (and, where sizes agree, its stale values) is kept, so
    /// a frame of the same size costs no allocation and no clearing.
    pub fn resize_for_overwrite(&mut self, width: u32, height: u32) {
        self.width = width;
        self.height = height;
        self.color
            .resize((width as usize) * (height as usize), Vec3::ZERO);
        self.layers.clear();
        self.rays = 0;
    }

    /// Pixels in the frame.
    pub fn pixel_count(&self) -> usize {
        self.color.len()
    }

    /// Writes exactly the layers of `method`'s registry row from the per-pixel outputs `pixels`
    /// (row-major, one per pixel; each layer in parallel). A layer of the row the family does
    /// not compute is [`RenderError::MissingLayer`], never a panic; a value of another kind than
    /// its layer's leaves the layer's empty value there (NaN, 0, `false`). A test renders
    /// every row on both backends and checks its layers.
    pub fn write_row_layers<P: PixelLayers>(
        &mut self,
        method: MethodId,
        pixels: &[P],
    ) -> Result<(), RenderError> {
        for &aov in method.info().aovs {
            if pixels.first().is_some_and(|p| p.value(aov).is_none()) {
                return Err(RenderError::MissingLayer {
                    method,
                    layer: aov.name(),
                });
            }
            let pixels = pixels.par_iter();
            match self.layer_mut(aov) {
                Layer::Vec3(out) => out.par_iter_mut().zip(pixels).for_each(|(o, p)| {
                    *o = match p.value(aov) {
                        Some(LayerValue::Vec3(v)) => v,
                        _ => Vec3::NAN,
                    }
                }),
                Layer::Count(out) => out.par_iter_mut().zip(pixels).for_each(|(o, p)| {
                    *o = match p.value(aov) {
                        Some(LayerValue::Count(v)) => v,
                        _ => 0,
                    }
                }),
                Layer::Flag(out) => out.par_iter_mut().zip(pixels).for_each(|(o, p)| {
                    *o = matches!(p.value(aov), Some(LayerValue::Flag(true)));
                }),
            }
        }
        Ok(())
    }

    /// The layers present with their AOVs, in a fixed order.
    pub fn layers(&self) -> impl Iterator<Item = (Aov, &Layer)> + '_ {
        self.layers.iter().map(|(aov, layer)| (*aov, layer))
    }

    /// The AOVs present.
    pub fn aovs(&self) -> impl Iterator<Item = Aov> + '_ {
        self.layers.keys().copied()
    }

    /// Whether the layer exists.
    pub fn has(&self, aov: Aov) -> bool {
        self.layers.contains_key(&aov)
    }

    /// The layer `aov` (mutable), created empty (NaN / 0 / false) when absent.
    pub fn layer_mut(&mut self, aov: Aov) -> &mut Layer {
        let n = self.pixel_count();
        let layer = self
            .layers
            .entry(aov)
            .or_insert_with(|| Layer::empty(aov.kind(), n));
        if layer.len() != n {
            *layer = Layer::empty(aov.kind(), n);
        }
        layer
    }

    /// Puts `layer` in as `aov`, replacing any layer of that name: for renderers that fill
    /// their layers in parallel, row by row, and hand them over whole.
    ///
    /// # Panics
    /// If the layer's type is not `aov`'s or its length is not the frame's pixel count (a
    /// programming error, not an input error).
    pub fn insert_layer(&mut self, aov: Aov, layer: Layer) {
        let kind = match &layer {
            Layer::Vec3(_) => AovKind::Vec3,
            Layer::Count(_) => AovKind::Count,
            Layer::Flag(_) => AovKind::Flag,
        };
        assert!(
            kind == aov.kind() && layer.len() == self.pixel_count(),
            "layer {} of {kind:?} × {} for a {:?} AOV of {} pixels",
            aov.name(),
            layer.len(),
            aov.kind(),
            self.pixel_count()
        );
        self.layers.insert(aov, layer);
    }

    /// A vector layer, if present.
    pub fn vec3(&self, aov: Aov) -> Option<&[Vec3]> {
        match self.layers.get(&aov)? {
            Layer::Vec3(v) => Some(v),
            _ => None,
        }
    }

    /// A count layer, if present.
    pub fn count(&self, aov: Aov) -> Option<&[u32]> {
        match self.layers.get(&aov)? {
            Layer::Count(v) => Some(v),
            _ => None,
        }
    }

    /// A flag layer, if present.
    pub fn flag(&self, aov: Aov) -> Option<&[bool]> {
        match self.layers.get(&aov)? {
            Layer::Flag(v) => Some(v),
            _ => None,
        }
    }

    /// A vector layer to write, created (NaN) when absent.
    ///
    /// # Panics
    /// If `aov` is not a vector AOV (a programming error, not an input error).
    pub fn vec3_mut(&mut self, aov: Aov) -> &mut [Vec3] {
        match self.layer_mut(aov) {
            Layer::Vec3(v) => v,
            _ => panic!("{} is not a vector AOV", aov.name()),
        }
    }

    /// A count layer to write, created (0) when absent.
    ///
    /// # Panics
    /// If `aov` is not a count AOV.
    pub fn count_mut(&mut self, aov: Aov) -> &mut [u32] {
        match self.layer_mut(aov) {
            Layer::Count(v) => v,
            _ => panic!("{} is not a count AOV", aov.name()),
        }
    }

    /// A flag layer to write, created (false) when absent.
    ///
    /// # Panics
    /// If `aov` is not a flag AOV.
    pub fn flag_mut(&mut self, aov: Aov) -> &mut [bool] {
        match self.layer_mut(aov) {
            Layer::Flag(v) => v,
            _ => panic!("{} is not a flag AOV", aov.name()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A family that computes coverage and `T2` only, and gives `T2` as a flag by mistake.
    struct Partial(bool);

    impl PixelLayers for Partial {
        fn value(&self, aov: Aov) -> Option<LayerValue> {
            match aov {
                Aov::Covered | Aov::Tir => Some(LayerValue::Flag(self.0)),
                Aov::T2 => Some(LayerValue::Flag(true)),
                _ => None,
            }
        }
    }

    /// The row's layers and only those are written; a value of the wrong kind leaves the
    /// layer's empty value; a layer the family does not compute is an error naming it.
    #[test]
    fn frames_get_exactly_the_row_layers() {
        let mut frame = Frame::new(2, 1);
        let pixels = [Partial(true), Partial(false)];
        // `single` writes covered, T2, tir.
        frame
            .write_row_layers(MethodId::Single, &pixels)
            .expect("single's layers");
        assert_eq!(
            frame.aovs().collect::<Vec<_>>(),
            [Aov::Covered, Aov::T2, Aov::Tir]
        );
        assert_eq!(frame.flag(Aov::Covered), Some(&[true, false][..]));
        assert!(frame.vec3(Aov::T2).expect("T2").iter().all(|v| v.is_nan()));
        // `wyman` also writes P2, N2 and the exit-normal source: not computed here.
        let err = frame
            .write_row_layers(MethodId::Wyman, &pixels)
            .expect_err("P2 is missing");
        assert!(err.to_string().contains("P2"), "{err}");
    }
}
