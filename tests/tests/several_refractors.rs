//! What each family does with several refractors (`docs/methods.md`, "Several refractors"),
//! held on `glass-behind-glass` (a small sphere, refractor 0, partly in front of a larger one,
//! here of IOR 1.33),
//! every method, on the CPU and on the GPU:
//!
//! * the image-space, nearby-geometry, distance-map and PVRR families follow refractor 0 and
//!   draw no other: their frames equal, bit for bit, the frames of the scene without the
//!   other refractors;
//! * `depth-peel` follows each ray through every refractor it crosses: the refractors its paths
//!   meet are the exact reference's on nearly every pixel (and with one layer, only the
//!   nearest refractor is ever met);
//! * the engine family draws every refractor as the engines draw several transmissive objects:
//!   each pixel is the one-refractor frame of the refractor nearest there (refractor 0 where
//!   both cover a pixel), so no glass is seen through another.

use std::sync::Arc;

use refract_cpu::CpuRenderer;
use refract_eval::load_scene;
use refract_gpu::GpuRenderer;
use refract_scene::{Aov, BackendId, Family, Frame, REGISTRY, Renderer, Scene};
use refract_tests::scenes::{method, render};
use refract_trace::ReferenceRenderer;

const WIDTH: u32 = 96;
const HEIGHT: u32 = 72;

/// The scene, and one scene per refractor holding that refractor alone (as refractor 0).
fn scenes() -> (Arc<Scene>, Vec<Arc<Scene>>) {
    let mut scene = load_scene("glass-behind-glass").expect("built-in").scene;
    // Another IOR for the rear sphere, so that a refractor drawn with refractor 0's IOR fails.
    scene.other_refractors[0].set_ior(1.33).expect("IOR");
    let alone = scene
        .refractors()
        .map(|r| {
            let mut one = scene.clone();
            one.refractor = r.clone();
            one.other_refractors.clear();
            Arc::new(one)
        })
        .collect();
    (Arc::new(scene), alone)
}

fn bits(frame: &Frame) -> Vec<[u32; 3]> {
    frame
        .color
        .iter()
        .map(|c| c.to_array().map(f32::to_bits))
        .collect()
}

fn check(backend: &str, renderer: &mut dyn Renderer, id: BackendId) {
    let (scene, alone) = scenes();
    assert_eq!(alone.len(), 2);
    let camera = scene.camera(WIDTH, HEIGHT).expect("camera");
    for info in REGISTRY.iter().filter(|m| m.backends.contains(&id)) {
        if info.family == Family::Reference {
            continue;
        }
        let params = method(info.id);
        let both = render(renderer, &scene, &camera, &params);
        let single: Vec<Frame> = alone
            .iter()
            .map(|s| render(renderer, s, &camera, &params))
            .collect();
        let name = info.name;
        if info.family == Family::DepthPeel {
            check_depth_peel(backend, renderer, &scene, &camera, &both);
            continue;
        }
        if info.family != Family::Engine {
            assert!(
                bits(&both) == bits(&single[0]),
                "{backend} {name}: the second refractor changed the frame"
            );
            continue;
        }
        let covered = |f: &Frame| f.flag(Aov::Covered).expect("covered").to_vec();
        let (front, back) = (covered(&single[0]), covered(&single[1]));
        let (both_bits, front_bits, back_bits) = (bits(&both), bits(&single[0]), bits(&single[1]));
        let (mut overlap, mut back_only, mut wrong) = (0, 0, 0);
        for i in 0..both_bits.len() {
            let expected = if front[i] {
                overlap += usize::from(back[i]);
                front_bits[i]
            } else {
                back_only += usize::from(back[i]);
                back_bits[i]
            };
            wrong += usize::from(both_bits[i] != expected);
        }
        println!("{backend} {name}: {overlap} overlapping, {back_only} rear-only pixels");
        assert!(
            overlap > 50 && back_only > 500,
            "{backend} {name}: {overlap} overlapping and {back_only} rear-only pixels"
        );
        assert_eq!(
            wrong, 0,
            "{backend} {name}: {wrong} pixels are not their nearest refractor's"
        );
        let both_covered = covered(&both);
        let union = (0..front.len()).filter(|&i| front[i] || back[i]).count();
        let drawn = both_covered.iter().filter(|c| **c).count();
        assert_eq!(drawn, union, "{backend} {name}: covered pixels");
    }
}

/// `depth-peel`'s `refractors_met` against the reference's: the same mask on at least 95 % of
/// the pixels both cover, and among them both refractors on the overlap; with one layer, no
/// path meets more than the refractor it starts on.
fn check_depth_peel(
    backend: &str,
    renderer: &mut dyn Renderer,
    scene: &Arc<Scene>,
    camera: &refract_core::Camera,
    frame: &Frame,
) {
    let reference = render(
        &mut ReferenceRenderer::new(),
        scene,
        camera,
        &method(refract_scene::MethodId::Reference),
    );
    let met = |f: &Frame| {
        f.count(Aov::RefractorsMet)
            .expect("refractors met")
            .to_vec()
    };
    let covered = |f: &Frame| f.flag(Aov::Covered).expect("covered").to_vec();
    let (peel_met, exact_met) = (met(frame), met(&reference));
    let (peel_covered, exact_covered) = (covered(frame), covered(&reference));
    let (mut both, mut same, mut two) = (0, 0, 0);
    for i in 0..peel_met.len() {
        if peel_covered[i] && exact_covered[i] {
            both += 1;
            same += usize::from(peel_met[i] == exact_met[i]);
            two += usize::from(exact_met[i] == 0b11 && peel_met[i] == 0b11);
        }
    }
    println!(
        "{backend} depth-peel: {same} of {both} pixels meet the reference's refractors, {two} both"
    );
    assert!(
        both > 1000 && two > 50,
        "{backend}: {both} covered, {two} meeting both"
    );
    assert!(
        same * 100 >= both * 95,
        "{backend}: {same} of {both} pixels agree"
    );
    let mut one_layer = method(refract_scene::MethodId::DepthPeel);
    one_layer.set("layers", "1", "test").expect("layers");
    let single = render(renderer, scene, camera, &one_layer);
    let single_met = met(&single);
    assert!(
        single_met.iter().all(|m| m.count_ones() <= 1),
        "{backend}: one layer met two refractors"
    );
}

#[test]
fn families_draw_several_refractors_as_documented_on_the_cpu() {
    check("cpu", &mut CpuRenderer::new(), BackendId::Cpu);
}

#[test]
fn families_draw_several_refractors_as_documented_on_the_gpu() {
    let Some(mut gpu) = GpuRenderer::for_tests() else {
        return;
    };
    check("gpu", &mut gpu, BackendId::Gpu);
}
