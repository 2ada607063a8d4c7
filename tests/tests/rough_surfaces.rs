//! What the methods do with rough surfaces (`docs/methods.md`, "Rough surfaces"): every
//! approximate method, on the CPU and on the GPU, renders `rough-glass` bit for bit as the same
//! spheres at roughness 0, while the reference's image changes.

use std::sync::Arc;

use refract_cpu::CpuRenderer;
use refract_eval::load_scene;
use refract_gpu::GpuRenderer;
use refract_scene::{BackendId, Family, Frame, MethodId, REGISTRY, Renderer, Scene};
use refract_tests::scenes::{method, render};
use refract_trace::ReferenceRenderer;

const WIDTH: u32 = 64;
const HEIGHT: u32 = 48;

/// `rough-glass`, and the same scene with every roughness set to 0.
fn scenes() -> (Arc<Scene>, Arc<Scene>) {
    let rough = load_scene("rough-glass").expect("built-in").scene;
    assert!(rough.has_roughness());
    let mut smooth = rough.clone();
    smooth.refractor.set_roughness(0.0).expect("roughness");
    for r in &mut smooth.other_refractors {
        r.set_roughness(0.0).expect("roughness");
    }
    assert!(!smooth.has_roughness());
    (Arc::new(rough), Arc::new(smooth))
}

fn bits(frame: &Frame) -> Vec<[u32; 3]> {
    frame
        .color
        .iter()
        .map(|c| c.to_array().map(f32::to_bits))
        .collect()
}

fn check(backend: &str, renderer: &mut dyn Renderer, id: BackendId) {
    let (rough, smooth) = scenes();
    let camera = rough.camera(WIDTH, HEIGHT).expect("camera");
    let mut checked = 0;
    for info in REGISTRY.iter().filter(|m| m.backends.contains(&id)) {
        if info.family == Family::Reference {
            continue;
        }
        let params = method(info.id);
        let a = render(renderer, &rough, &camera, &params);
        let b = render(renderer, &smooth, &camera, &params);
        assert!(
            bits(&a) == bits(&b),
            "{backend} {}: the roughness changed the frame",
            info.name
        );
        checked += 1;
    }
    assert!(checked >= 10, "{backend}: {checked} methods");
}

#[test]
fn approximate_methods_render_rough_glass_as_smooth_on_the_cpu() {
    check("cpu", &mut CpuRenderer::new(), BackendId::Cpu);
}

#[test]
fn approximate_methods_render_rough_glass_as_smooth_on_the_gpu() {
    let Some(mut gpu) = GpuRenderer::for_tests() else {
        return;
    };
    check("gpu", &mut gpu, BackendId::Gpu);
}

/// The control: the reference traces the roughness, so its frame changes on the rough spheres,
/// and only there: elsewhere (pixels with no rough sphere among their 3×3 neighbours' centre
/// paths) both frames share every sample.
#[test]
fn the_reference_sees_the_roughness() {
    let (rough, smooth) = scenes();
    let camera = rough.camera(WIDTH, HEIGHT).expect("camera");
    let mut params = method(MethodId::Reference);
    params.set("spp", "16", "test").expect("spp");
    let a = render(&mut ReferenceRenderer::new(), &rough, &camera, &params);
    let b = render(&mut ReferenceRenderer::new(), &smooth, &camera, &params);
    let met = a
        .count(refract_scene::Aov::RefractorsMet)
        .expect("refractors met");
    // Refractors 1-3 are the rough ones (bits 1-3).
    let near_rough = |x: i64, y: i64| {
        (-1..=1).any(|dy| {
            (-1..=1).any(|dx| {
                let (u, v) = (x + dx, y + dy);
                (0..i64::from(WIDTH)).contains(&u)
                    && (0..i64::from(HEIGHT)).contains(&v)
                    && met[(v * i64::from(WIDTH) + u) as usize] & 0b1110 != 0
            })
        })
    };
    let (mut changed_rough, mut changed_elsewhere) = (0, 0);
    for (i, (p, q)) in a.color.iter().zip(&b.color).enumerate() {
        let changed = (*p - *q).abs().max_element() > 1e-3;
        let (x, y) = ((i as u32 % WIDTH) as i64, (i as u32 / WIDTH) as i64);
        if met[i] & 0b1110 != 0 {
            changed_rough += usize::from(changed);
        } else if !near_rough(x, y) {
            changed_elsewhere += usize::from(changed);
        }
    }
    println!("reference: {changed_rough} rough-sphere pixels changed, {changed_elsewhere} others");
    assert!(changed_rough > 100, "{changed_rough}");
    assert_eq!(changed_elsewhere, 0);
}
