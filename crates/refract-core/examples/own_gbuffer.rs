//! Driving Wyman 2005a's two-interface kernel from your own G-buffer, with refract-core alone.
//!
//! A renderer rasterises the refractor twice: back faces into a (normal, distance) buffer and
//! front faces into a (P1, N1, d_N) buffer. Here both buffers are filled analytically for a unit
//! glass sphere, then every covered pixel runs `two_interface` and reports where its refracted
//! ray leaves. Run: `cargo run -p refract-core --example own_gbuffer`.

use glam::{Vec2, Vec3};
use refract_core::kernel::{
    BackFaceSample, BackFaceSampler, FrontSurface, ImageSpaceParams, two_interface,
};
use refract_core::{Camera, CameraDesc, DistanceMode, ExitNormalSource, TirPolicy};

const SIZE: u32 = 48;

/// The back-face buffer as a renderer would store it: per pixel the far surface's normal and
/// its distance from the eye, `None` outside the silhouette.
struct BackFaceBuffer {
    width: u32,
    texels: Vec<Option<BackFaceSample>>,
}

impl BackFaceSampler for BackFaceBuffer {
    /// Nearest texel, as a `textureLoad` would read it.
    fn back_face(&self, uv_px: Vec2) -> Option<BackFaceSample> {
        if uv_px.x < 0.0 || uv_px.y < 0.0 {
            return None;
        }
        let (x, y) = (uv_px.x as u32, uv_px.y as u32);
        if x >= self.width {
            return None;
        }
        *self.texels.get((y * self.width + x) as usize)?
    }
}

/// Near and far intersections of a pixel ray with the unit sphere.
fn sphere_hits(camera: &Camera, uv: Vec2) -> Option<(Vec3, f32, f32)> {
    let ray = camera.pixel_ray(uv);
    let b = ray.origin.dot(ray.dir);
    let disc = b * b - (ray.origin.length_squared() - 1.0);
    (disc >= 0.0).then(|| (ray.dir, -b - disc.sqrt(), -b + disc.sqrt()))
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let camera = Camera::new(CameraDesc {
        width: SIZE,
        height: SIZE,
        ..CameraDesc::default()
    })?;
    let pixels = || (0..SIZE * SIZE).map(|i| Camera::pixel_center(i % SIZE, i / SIZE));
    // "Pass 1": back faces.
    let back = BackFaceBuffer {
        width: SIZE,
        texels: pixels()
            .map(|uv| {
                sphere_hits(&camera, uv).map(|(dir, _, far)| BackFaceSample {
                    n_ws: camera.eye() + far * dir,
                    distance: far,
                })
            })
            .collect(),
    };
    // "Pass 2": front faces, and the kernel per covered pixel.
    let params =
        ImageSpaceParams::new(1.5, DistanceMode::Interpolated, TirPolicy::ClampToCritical)?;
    let (mut covered, mut from_back_face, mut tir, mut max_deviation) = (0, 0, 0, 0.0f32);
    for uv in pixels() {
        let Some((dir, near, _)) = sphere_hits(&camera, uv) else {
            continue;
        };
        let p1 = camera.eye() + near * dir;
        let front = FrontSurface {
            p1_ws: p1,
            n1_ws: p1,
            d_n: 2.0, // a unit sphere's diameter along −N
        };
        let path = two_interface(&camera, uv, &front, &back, &params)?;
        covered += 1;
        from_back_face += usize::from(path.n2_source == ExitNormalSource::BackFace);
        tir += usize::from(path.tir_exit);
        max_deviation = max_deviation.max(path.t2.angle_between(dir).to_degrees());
    }
    println!(
        "{covered} refractor pixels: N2 from the back-face buffer at {from_back_face}, TIR at the exit at {tir}; \
         rays deviate up to {max_deviation:.1}° from the view direction"
    );
    Ok(())
}
