//! What the methods do with rough surfaces and dispersive glass (`docs/methods.md`, "Rough
//! surfaces", "Dispersion"): every approximate method outside the engine family, on the CPU and
//! on the GPU, renders `rough-glass` bit for bit as the same spheres at roughness 0, while the
//! reference's image changes; the engine models blur each sphere more the rougher it is (three.js's,
//! Bevy's, Godot's, HDRP's and Filament's rules). On `prism`, a method with the `wavelengths`
//! parameter renders, at 1, the prism without dispersion bit for bit and, at `N`, the bins'
//! weighted sum of its frames of the clear prism at the bins' indices, with the layers of the
//! clear prism; the engine models render the clear prism, but three.js's (`volume-thickness`
//! without a depth test), whose channels are, bit for bit, its frames of the clear prism at its
//! three indices.

use std::sync::Arc;

use refract_core::Camera;
use refract_cpu::CpuRenderer;
use refract_eval::load_scene;
use refract_gpu::GpuRenderer;
use refract_scene::{
    Aov, BackendId, Family, Frame, MethodId, MethodParams, REGISTRY, Renderer, Scene,
};
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

/// `prism`, and the same prism without dispersion.
fn prisms() -> (Arc<Scene>, Arc<Scene>) {
    let dispersive = load_scene("prism").expect("built-in").scene;
    assert!(dispersive.has_dispersion());
    let mut clear = dispersive.clone();
    clear.refractor.set_abbe(f32::INFINITY).expect("abbe");
    assert!(!clear.has_dispersion());
    (Arc::new(dispersive), Arc::new(clear))
}

fn check(backend: &str, renderer: &mut dyn Renderer, id: BackendId) {
    for (feature, (with, without)) in [("roughness", scenes()), ("dispersion", prisms())] {
        let camera = with.camera(WIDTH, HEIGHT).expect("camera");
        let mut checked = 0;
        for info in REGISTRY.iter().filter(|m| m.backends.contains(&id)) {
            // The engine models blur rough glass as their engines do and three.js's disperses:
            // their own tests below.
            if info.family == Family::Reference
                || (feature == "roughness" && info.family == Family::Engine)
                || (feature == "dispersion" && info.id == MethodId::VolumeThickness)
            {
                continue;
            }
            let mut params = method(info.id);
            if params.wavelengths().is_some() {
                params.set("wavelengths", "1", "test").expect("wavelengths");
            }
            let a = render(renderer, &with, &camera, &params);
            let b = render(renderer, &without, &camera, &params);
            assert!(
                bits(&a) == bits(&b),
                "{backend} {}: the {feature} changed the frame",
                info.name
            );
            checked += 1;
        }
        assert!(checked >= 8, "{backend} {feature}: {checked} methods");
    }
}

#[test]
fn approximate_methods_ignore_roughness_and_one_wavelength_ignores_dispersion_on_the_cpu() {
    check("cpu", &mut CpuRenderer::new(), BackendId::Cpu);
}

#[test]
fn approximate_methods_ignore_roughness_and_one_wavelength_ignores_dispersion_on_the_gpu() {
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

/// The control for dispersion: the reference renders the prism spectrally, so its frame changes
/// where the pixels see the slits through the prism (over 100 of the 64 × 48 frame's pixels
/// differ by more than 0.05 at 16 samples), while elsewhere both frames see the same wall and
/// slits directly, the spectral one through its wavelength estimate: there the means of the two
/// frames agree to 2 % per channel.
#[test]
fn the_reference_sees_the_dispersion() {
    let (dispersive, clear) = prisms();
    let camera = dispersive.camera(WIDTH, HEIGHT).expect("camera");
    let mut params = method(MethodId::Reference);
    params.set("spp", "16", "test").expect("spp");
    let a = render(&mut ReferenceRenderer::new(), &dispersive, &camera, &params);
    let b = render(&mut ReferenceRenderer::new(), &clear, &camera, &params);
    let covered = a.flag(refract_scene::Aov::Covered).expect("covered");
    let mut changed_prism = 0;
    let (mut sum_a, mut sum_b) = (glam::Vec3::ZERO, glam::Vec3::ZERO);
    for (i, (p, q)) in a.color.iter().zip(&b.color).enumerate() {
        if covered[i] {
            changed_prism += usize::from((*p - *q).abs().max_element() > 0.05);
        } else {
            sum_a += *p;
            sum_b += *q;
        }
    }
    let relative = ((sum_a - sum_b) / sum_b).abs().max_element();
    println!(
        "reference: {changed_prism} prism pixels changed; elsewhere the means differ by {relative}"
    );
    assert!(changed_prism > 100, "{changed_prism}");
    assert!(relative < 0.02, "{relative}");
}

/// three.js's dispersion (`docs/methods.md`, "Dispersion"): on `prism`, `volume-thickness`
/// (three.js: no depth test) reads red, green and blue through the indices `n_d − s`, `n_d`,
/// `n_d + s`, `s = (n_d − 1) · 0.025 · 20 / V_d` = 0.00833 at V_d 30: each channel of its frame
/// is, bit for bit, that channel of its frame of the clear prism at that index, on both
/// backends; at 256 × 192 the red and blue channels differ from the clear prism's on more than
/// 20 pixels (the slits' edges move by a pixel or two), and Bevy's model (`depth-test=reject`)
/// has no dispersion.
fn check_threejs_dispersion(backend: &str, renderer: &mut dyn Renderer) {
    let (dispersive, clear) = prisms();
    let camera = dispersive.camera(256, 192).expect("camera");
    let params = method(MethodId::VolumeThickness);
    let frame = render(renderer, &dispersive, &camera, &params);
    let ior = dispersive.refractor.ior();
    let spread = (ior - 1.0) * 0.025 * (20.0 / 30.0);
    let mut changed = 0;
    for (channel, offset) in [(0, -spread), (1, 0.0), (2, spread)] {
        let mut at = (*clear).clone();
        at.refractor.set_ior(ior + offset).expect("ior");
        let single = render(renderer, &Arc::new(at), &camera, &params);
        for (i, (a, b)) in frame.color.iter().zip(&single.color).enumerate() {
            assert_eq!(
                a[channel].to_bits(),
                b[channel].to_bits(),
                "{backend}: pixel {i} channel {channel}"
            );
        }
        if channel != 1 {
            let plain = render(renderer, &clear, &camera, &params);
            changed += frame
                .color
                .iter()
                .zip(&plain.color)
                .filter(|(a, b)| (a[channel] - b[channel]).abs() > 1e-3)
                .count();
        }
    }
    println!("{backend}: {changed} red and blue values changed");
    assert!(changed > 20, "{backend}: {changed} channel values changed");
    let mut bevy = method(MethodId::VolumeThickness);
    bevy.set("depth-test", "reject", "test")
        .expect("depth-test");
    let a = render(renderer, &dispersive, &camera, &bevy);
    let b = render(renderer, &clear, &camera, &bevy);
    assert!(bits(&a) == bits(&b), "{backend}: Bevy's model dispersed");
}

#[test]
fn threejs_disperses_through_three_indices_on_the_cpu() {
    check_threejs_dispersion("cpu", &mut CpuRenderer::new());
}

#[test]
fn threejs_disperses_through_three_indices_on_the_gpu() {
    let Some(mut gpu) = GpuRenderer::for_tests() else {
        return;
    };
    check_threejs_dispersion("gpu", &mut gpu);
}

/// Filament's dispersion (`docs/methods.md`, "Dispersion";
/// `refract_core::engine_dispersion`): on `prism`, `proxy-sphere` with Filament's lookup reads
/// four paths per pixel at `n_j = n + f o_j + ξ(pixel)`, `f = (n − 1)/V_d`, and its colour is
/// `max(Σ_j K_j C_j, 0)` with `C_j` the pixel's colour in the model's frame of the clear prism
/// at `n_j`: held on every pixel the dispersion moves and 24 others (bit for bit on the CPU, to
/// 1e-5 on the GPU, whose matrix products may fuse); the dispersion changes more than 20 pixels of 256 × 192 by more than
/// 1e-3, and Filament's box model (no `solid` refraction) does not disperse.
fn check_filament_dispersion(backend: &str, renderer: &mut dyn Renderer, exact: bool) {
    use refract_core::engine_dispersion::EngineDispersion;
    let (dispersive, clear) = prisms();
    let camera = dispersive.camera(256, 192).expect("camera");
    let mut params = method(MethodId::ProxySphere);
    params.set("lookup", "filament", "test").expect("lookup");
    let frame = render(renderer, &dispersive, &camera, &params);
    let plain = render(renderer, &clear, &camera, &params);
    let covered = frame.flag(Aov::Covered).expect("covered").to_vec();
    let prism: Vec<usize> = (0..covered.len()).filter(|&i| covered[i]).collect();
    assert!(
        prism.len() > 2000,
        "{backend}: {} prism pixels",
        prism.len()
    );
    let ior = dispersive.refractor.ior();
    let scheme = EngineDispersion::filament(ior, dispersive.refractor.abbe());
    assert_eq!(scheme.lookups(), 4);
    // The pixels the dispersion moves (whose four reads differ), and 24 others.
    let moved = (0..frame.color.len())
        .filter(|&i| (frame.color[i] - plain.color[i]).abs().max_element() > 1e-3);
    let mut checked: Vec<usize> = prism.iter().copied().step_by(prism.len() / 24).collect();
    checked.extend(moved);
    for &i in &checked {
        let (x, y) = (i as u32 % camera.width(), i as u32 / camera.width());
        let uv = Camera::pixel_center(x, y);
        let mut sum = glam::Vec3::ZERO;
        for j in 0..4 {
            let (n_j, matrix) = scheme.lookup(ior, j, uv);
            let mut at = (*clear).clone();
            at.refractor.set_ior(n_j).expect("ior");
            let single = render(renderer, &Arc::new(at), &camera, &params);
            sum += matrix * single.color[i];
        }
        let expected = sum.max(glam::Vec3::ZERO);
        let got = frame.color[i];
        if exact {
            assert_eq!(
                got.to_array().map(f32::to_bits),
                expected.to_array().map(f32::to_bits),
                "{backend}: pixel ({x}, {y}): {got} vs {expected}"
            );
        } else {
            assert!(
                (got - expected).abs().max_element() <= 1e-5,
                "{backend}: pixel ({x}, {y}): {got} vs {expected}"
            );
        }
    }
    let changed = frame
        .color
        .iter()
        .zip(&plain.color)
        .filter(|(a, b)| (**a - **b).abs().max_element() > 1e-3)
        .count();
    println!("{backend}: Filament's dispersion changed {changed} pixels");
    assert!(changed > 20, "{backend}: {changed} pixels changed");
    let mut the_box = method(MethodId::ProxyBox);
    the_box.set("lookup", "filament", "test").expect("lookup");
    let a = render(renderer, &dispersive, &camera, &the_box);
    let b = render(renderer, &clear, &camera, &the_box);
    assert!(bits(&a) == bits(&b), "{backend}: Filament's box dispersed");
}

#[test]
fn filament_disperses_through_four_wavelengths_on_the_cpu() {
    check_filament_dispersion("cpu", &mut CpuRenderer::new(), true);
}

#[test]
fn filament_disperses_through_four_wavelengths_on_the_gpu() {
    let Some(mut gpu) = GpuRenderer::for_tests() else {
        return;
    };
    check_filament_dispersion("gpu", &mut gpu, false);
}

/// `wavelengths = N` on `prism` (`refract_scene::render_dispersive`): the colour is
/// `Σᵢ Wᵢ ⊙ Cᵢ` with `Cᵢ` the method's frame of the clear prism at the index of bin `i`'s
/// wavelength (so every family reads the frame's wavelength wherever it reads the index), and
/// the layers are the clear prism's; the dispersion moves the colour of more than 20 pixels
/// of 64 × 48 by more than 1e-3 for every method but `kay-greenberg` (the prism spreads the
/// slits).
fn check_wavelength_sums(backend: &str, renderer: &mut dyn Renderer, id: BackendId) {
    let (dispersive, clear) = prisms();
    let camera = dispersive.camera(WIDTH, HEIGHT).expect("camera");
    let mut checked = 0;
    for info in REGISTRY.iter().filter(|m| m.backends.contains(&id)) {
        let mut params = method(info.id);
        let Some(wavelengths) = params.wavelengths() else {
            continue;
        };
        assert_eq!(wavelengths.count(), 3, "{}", info.name);
        for n in [3, 5] {
            params
                .set("wavelengths", &n.to_string(), "test")
                .expect("wavelengths");
            let bins = refract_scene::dispersion_bins(&dispersive, &params).expect("bins");
            assert_eq!(bins.as_slice().len(), n);
            let frame = render(renderer, &dispersive, &camera, &params);
            let plain = render(renderer, &clear, &camera, &params);
            let mut expected = vec![glam::Vec3::ZERO; frame.color.len()];
            for (i, bin) in bins.as_slice().iter().enumerate() {
                let mut at = (*clear).clone();
                let ior = dispersive.refractor.ior_at(Some(bin.lambda));
                at.refractor.set_ior(ior).expect("ior");
                let single = render(renderer, &Arc::new(at), &camera, &params);
                for (e, c) in expected.iter_mut().zip(&single.color) {
                    if i == 0 {
                        *e = bin.weight * *c;
                    } else {
                        *e += bin.weight * *c;
                    }
                }
            }
            for (k, (a, e)) in frame.color.iter().zip(&expected).enumerate() {
                assert!(
                    a.to_array().map(f32::to_bits) == e.to_array().map(f32::to_bits),
                    "{backend} {} N {n}: pixel {k}: {a} vs {e}",
                    info.name
                );
            }
            // Debug text: NaN layers compare equal to themselves.
            let layers = |f: &Frame| format!("{:?}", f.layers().collect::<Vec<_>>());
            assert_eq!(frame.aovs().count(), info.aovs.len(), "{}", info.name);
            assert!(
                layers(&frame) == layers(&plain),
                "{backend} {}: the layers differ from the clear prism's",
                info.name
            );
            let moved = frame
                .color
                .iter()
                .zip(&plain.color)
                .filter(|(a, b)| (**a - **b).abs().max_element() > 1e-3)
                .count();
            println!("{backend} {} N {n}: {moved} pixels changed", info.name);
            // Kay and Greenberg's lookup is the exit point projected, whatever the direction
            // leaving it: the index moves it by less than a texel here. The family's other
            // methods read the wavelength through the same code.
            assert!(
                moved > 20 || info.id == MethodId::KayGreenberg,
                "{backend} {} N {n}: {moved} pixels changed",
                info.name
            );
        }
        checked += 1;
    }
    assert!(checked >= 11, "{backend}: {checked} methods");
}

#[test]
fn wavelengths_sum_the_frames_at_their_indices_on_the_cpu() {
    check_wavelength_sums("cpu", &mut CpuRenderer::new(), BackendId::Cpu);
}

#[test]
fn wavelengths_sum_the_frames_at_their_indices_on_the_gpu() {
    let Some(mut gpu) = GpuRenderer::for_tests() else {
        return;
    };
    check_wavelength_sums("gpu", &mut gpu, BackendId::Gpu);
}

/// The engine models that blur rough glass, with the settings that select them: three.js's
/// (`volume-thickness`), Bevy's (`volume-thickness`, `depth-test=reject`), Godot's
/// (`screen-offset`), HDRP's (`proxy-sphere`, `proxy-box`, `proxy-thin` with HDRP's lookup).
fn blurring_models() -> Vec<(&'static str, MethodParams)> {
    let mut bevy = method(MethodId::VolumeThickness);
    bevy.set("depth-test", "reject", "test")
        .expect("depth-test");
    let mut models = vec![
        ("three.js", method(MethodId::VolumeThickness)),
        ("Bevy", bevy),
        ("Godot", method(MethodId::ScreenOffset)),
    ];
    for (engine, lookup) in [("HDRP", "hdrp"), ("Filament", "filament")] {
        for id in [
            MethodId::ProxySphere,
            MethodId::ProxyBox,
            MethodId::ProxyThin,
        ] {
            let mut params = method(id);
            params.set("lookup", lookup, "test").expect("lookup");
            models.push((engine, params));
        }
    }
    models
}

/// Whether `engine`'s model blurs a sphere of `roughness` on `scene` through `camera`: every
/// model's does above roughness 0 but Filament's, whose LOD is 0 below `2^(−offset/2)`
/// (`refract_core::screen_mips::filament_lod`).
fn blurs(engine: &str, scene: &Scene, camera: &Camera, roughness: f32) -> bool {
    if engine != "Filament" {
        return roughness > 0.0;
    }
    let size = glam::UVec2::new(camera.width(), camera.height());
    let ior = scene.refractor.ior();
    refract_core::screen_mips::filament_lod(size, camera.desc().fov_y, roughness, ior) > 0.0
}

/// The engines' rough models (`docs/methods.md`, "Rough surfaces"): on `rough-glass` with one
/// sphere rough at a time (the others at 0), each blurring model's frame differs from its
/// all-smooth frame only by that sphere's blur, and more the rougher it is: the mean |change|
/// over the frame rises with roughness 0.1, 0.3, 0.6, and a sphere at roughness 0 changes
/// nothing; so does a sphere whose Filament LOD is 0 (roughness 0.1 at 128 × 96: [`blurs`]).
fn check_engine_blur(backend: &str, renderer: &mut dyn Renderer) {
    let (rough, smooth) = scenes();
    let camera = rough.camera(128, 96).expect("camera");
    for (engine, params) in blurring_models() {
        let plain = render(renderer, &smooth, &camera, &params);
        let mut changes = Vec::new();
        for k in 0..4 {
            let roughness = rough.refractor_at(k).expect("sphere").roughness();
            let mut one = (*smooth).clone();
            let sphere = if k == 0 {
                &mut one.refractor
            } else {
                &mut one.other_refractors[k - 1]
            };
            sphere.set_roughness(roughness).expect("roughness");
            let frame = render(renderer, &Arc::new(one), &camera, &params);
            let change = frame
                .color
                .iter()
                .zip(&plain.color)
                .map(|(a, b)| f64::from((*a - *b).abs().element_sum()))
                .sum::<f64>()
                / frame.color.len() as f64;
            changes.push(change);
        }
        println!(
            "{backend} {engine} {}: mean |change| {changes:.5?}",
            params.id()
        );
        assert_eq!(
            changes[0], 0.0,
            "{backend} {engine}: roughness 0 changed the frame"
        );
        let mut previous = 0.0;
        for (k, change) in changes.iter().enumerate().skip(1) {
            let roughness = rough.refractor_at(k).expect("sphere").roughness();
            if blurs(engine, &rough, &camera, roughness) {
                assert!(
                    *change > previous,
                    "{backend} {engine} {}: roughness {roughness}: {changes:?}",
                    params.id()
                );
                previous = *change;
            } else {
                assert_eq!(
                    *change,
                    0.0,
                    "{backend} {engine} {}: roughness {roughness} reads no mip",
                    params.id()
                );
            }
        }
        assert!(previous > 0.0, "{backend} {engine}: nothing blurred");
    }
}

#[test]
fn engines_blur_rough_glass_by_its_roughness_on_the_cpu() {
    check_engine_blur("cpu", &mut CpuRenderer::new());
}

#[test]
fn engines_blur_rough_glass_by_its_roughness_on_the_gpu() {
    let Some(mut gpu) = GpuRenderer::for_tests() else {
        return;
    };
    check_engine_blur("gpu", &mut gpu);
}

/// The engines' blurred frames agree between the backends: on `rough-glass` at 128 × 96,
/// colours differ by more than 2e-3 in any channel on at most 1 % of the pixels, for each
/// blurring model (the filters' sums run in the same order; the pyramid's block sums in
/// another, and the lat-long environment seen through the screen texture differs by float
/// rounding).
#[test]
fn engine_blur_agrees_between_the_backends() {
    let Some(mut gpu) = GpuRenderer::for_tests() else {
        return;
    };
    let (rough, _) = scenes();
    let camera = rough.camera(128, 96).expect("camera");
    for (engine, params) in blurring_models() {
        let a = render(&mut CpuRenderer::new(), &rough, &camera, &params);
        let b = render(&mut gpu, &rough, &camera, &params);
        let differ = a
            .color
            .iter()
            .zip(&b.color)
            .filter(|(a, b)| (**a - **b).abs().max_element() > 2e-3)
            .count();
        let share = differ as f64 / a.color.len() as f64;
        println!(
            "{engine} {} on rough-glass: {differ} pixels differ by > 2e-3 ({share:.4})",
            params.id()
        );
        assert!(
            share <= 0.01,
            "{engine}: {differ} of {} pixels",
            a.color.len()
        );
    }
}
