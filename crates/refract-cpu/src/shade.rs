//! The per-pixel work of a frame, eight pixels at a time: each row's covered pixels go through
//! refract-core's lane kernels ([`two_interface_x8`], [`one_interface_x8`]) in groups of eight,
//! its background pixels through the eight-lane camera rays and environment lookup. Lanes are
//! bit-identical to the scalar kernels, so grouping changes no pixel.

use glam::{Vec2, Vec3};
use refract_core::Camera;
use refract_core::kernel::{FrontSurface, ImageSpaceParams};
use refract_core::kernel_x8::{one_interface_x8, two_interface_x8};
use refract_core::lanes::{LANES, Vec2x8, Vec3x8};
use refract_trace::Environment;

use crate::buffers::BackFaces;
use crate::raster::Texel;
use crate::render::MethodAov;

/// What the per-pixel work of a frame reads.
pub(crate) struct ShadeContext<'a> {
    /// The back faces (two-interface methods), or `None` (`single`).
    pub back: Option<&'a BackFaces>,
    pub environment: &'a Environment,
    pub camera: &'a Camera,
    pub kernel: &'a ImageSpaceParams,
}

/// Up to eight pixels of one row waiting for the lane kernels.
struct Group<T> {
    x: [u32; LANES],
    items: [T; LANES],
    len: usize,
}

impl<T: Copy> Group<T> {
    fn new(filler: T) -> Self {
        Self {
            x: [0; LANES],
            items: [filler; LANES],
            len: 0,
        }
    }

    /// Adds a pixel; true when the group is full.
    #[inline]
    fn push(&mut self, x: u32, item: T) -> bool {
        self.x[self.len] = x;
        self.items[self.len] = item;
        self.len += 1;
        self.len == LANES
    }

    /// Pads the unused lanes with copies of lane 0 (their results are dropped).
    fn pad(&mut self) {
        for i in self.len..LANES {
            self.x[i] = self.x[0];
            self.items[i] = self.items[0];
        }
    }
}

/// Where a row's results go.
struct RowOut<'o> {
    colors: &'o mut [Vec3],
    aovs: Option<&'o mut [MethodAov]>,
}

impl RowOut<'_> {
    #[inline]
    fn write(&mut self, x: u32, color: Vec3, aov: impl FnOnce() -> MethodAov) {
        self.colors[x as usize] = color;
        if let Some(aovs) = self.aovs.as_deref_mut() {
            aovs[x as usize] = aov();
        }
    }
}

impl ShadeContext<'_> {
    /// Shades row `y`: `front(x)` is the front surface seen at pixel `x` (or none); colours go to
    /// `colors` and, when given, AOVs to `aovs` (both one row long).
    pub fn row(
        &self,
        y: u32,
        front: impl Fn(u32) -> Option<Texel>,
        colors: &mut [Vec3],
        aovs: Option<&mut [MethodAov]>,
    ) {
        let filler = FrontSurface {
            p1_ws: Vec3::ZERO,
            n1_ws: Vec3::Z,
            d_n: 0.0,
        };
        let mut out = RowOut { colors, aovs };
        let mut covered = Group::new(filler);
        let mut background = Group::new(());
        for x in 0..out.colors.len() as u32 {
            match front(x) {
                Some(texel) => {
                    let surface = FrontSurface {
                        p1_ws: texel.p_ws,
                        n1_ws: texel.n_ws,
                        d_n: texel.scalar,
                    };
                    if covered.push(x, surface) {
                        self.covered(&covered, y, &mut out);
                        covered.len = 0;
                    }
                }
                None => {
                    if background.push(x, ()) {
                        self.background(&background, y, &mut out);
                        background.len = 0;
                    }
                }
            }
        }
        if covered.len > 0 {
            covered.pad();
            self.covered(&covered, y, &mut out);
        }
        if background.len > 0 {
            background.pad();
            self.background(&background, y, &mut out);
        }
    }

    /// Eight pixels that see the environment directly.
    fn background(&self, group: &Group<()>, y: u32, out: &mut RowOut<'_>) {
        let uv = group.x.map(|x| Camera::pixel_center(x, y));
        let dirs = self.camera.pixel_ray_dir_x8(Vec2x8::from_lanes(&uv));
        let colors = self.environment.radiance_x8(dirs).to_lanes();
        for (&x, &color) in group.x.iter().zip(&colors).take(group.len) {
            out.write(x, color, || MethodAov::BACKGROUND);
        }
    }

    /// Eight pixels that see the refractor: the kernel, then the environment along `T2` (or
    /// `T1` for `single`); black where the kernel reports a degenerate input or the TIR policy
    /// absorbs the ray.
    fn covered(&self, group: &Group<FrontSurface>, y: u32, out: &mut RowOut<'_>) {
        const COVERED: MethodAov = MethodAov {
            covered: true,
            ..MethodAov::BACKGROUND
        };
        // Lanes that look nothing up (degenerate input, absorbed ray) are black.
        let lookup = |direction: Option<Vec3>| direction.unwrap_or(Vec3::Y);
        match self.back {
            None => {
                let paths = one_interface_x8(self.camera, &group.items, self.kernel);
                let directions = paths.each_ref().map(|p| p.as_ref().ok().map(|p| p.t1));
                let radiance = self.radiance(directions.map(lookup));
                for (i, path) in paths.iter().enumerate().take(group.len) {
                    match path {
                        Ok(path) => out.write(group.x[i], radiance[i], || MethodAov {
                            t2: path.t1,
                            tir: path.tir_entry,
                            ..COVERED
                        }),
                        Err(_) => out.write(group.x[i], Vec3::ZERO, || COVERED),
                    }
                }
            }
            Some(back) => {
                let uv: [Vec2; LANES] = group.x.map(|x| Camera::pixel_center(x, y));
                let paths = two_interface_x8(self.camera, &uv, &group.items, back, self.kernel);
                let directions = paths
                    .each_ref()
                    .map(|p| p.as_ref().ok().map(|p| p.t2).filter(|t2| *t2 != Vec3::ZERO));
                let radiance = self.radiance(directions.map(lookup));
                for (i, path) in paths.iter().enumerate().take(group.len) {
                    let color = if directions[i].is_some() {
                        radiance[i]
                    } else {
                        Vec3::ZERO
                    };
                    match path {
                        Ok(path) => out.write(group.x[i], color, || MethodAov {
                            p2: path.p2,
                            t2: path.t2,
                            n2: path.n2,
                            n2_source: Some(path.n2_source),
                            tir: path.tir_exit || path.entry.tir_entry,
                            ..COVERED
                        }),
                        Err(_) => out.write(group.x[i], color, || COVERED),
                    }
                }
            }
        }
    }

    #[inline]
    fn radiance(&self, directions: [Vec3; LANES]) -> [Vec3; LANES] {
        self.environment
            .radiance_x8(Vec3x8::from_lanes(&directions))
            .to_lanes()
    }
}
