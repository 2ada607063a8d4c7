//! The Umenhoffer et al. 2007 section of `docs/claims.md` (GPU Gems 3 ch. 17, layered distance
//! maps): error against the reference vs the maximum depth (Fig. 17-8), linear/secant step
//! counts (Fig. 17-6), min-max acceleration (§17.4), the glass sphere that reflects and refracts
//! (Fig. 17-9), and `distance-map` vs `wyman` on the glass-in-environment scenes. All on the CPU
//! backend.

use std::fmt::Write as _;
use std::sync::Arc;

use glam::Vec3;

use refract_eval::load_scene;
use refract_scene::{MethodId, MethodParams, Scene, TraceMode};

use super::inventory::{Inventory, Ledger, Verdict};
use super::{Bench, ClaimsArgs, Race, less, pct, value};
use crate::data_scenes;
use crate::progress::Progress;
use crate::timing::spread;

/// The chapter's setting (§17.4): 800 × 600, 3 layers of 6 × 512², depth 2.
const CHAPTER_SIZE: (u32, u32) = (800, 600);

/// U2: per round, whether its median frame of `ms` milliseconds runs at `fps` or more.
fn at_frame_rate(ms: &[f64], fps: f64) -> Vec<bool> {
    ms.iter().map(|&t| t <= 1e3 / fps).collect()
}

/// U9: per round, whether the deeper frame's time over the shallower's is at most `bar`.
fn at_most_ratio(ratios: &[f64], bar: f64) -> Vec<bool> {
    ratios.iter().map(|&r| r <= bar).collect()
}

/// The frame rates of frames taking `ms` milliseconds, slowest to fastest (`lo–hi`).
fn fps_range(ms: &[f64]) -> String {
    let slowest = ms.iter().copied().fold(f64::NAN, f64::max);
    let fastest = ms.iter().copied().fold(f64::NAN, f64::min);
    format!("{:.1}–{:.1}", 1e3 / slowest, 1e3 / fastest)
}

fn dm(settings: &[(&str, &str)]) -> crate::Result<MethodParams> {
    let mut params = MethodParams::defaults(MethodId::DistanceMap);
    for (name, v) in settings {
        params.set(name, v, "claims")?;
    }
    Ok(params)
}

/// U1 and U4 on one scene: from each pixel where the eye sees the specular object, its
/// reflected ray searched in the distance map against the exact ray's first hit.
#[derive(Debug, Default, PartialEq)]
struct SearchCheck {
    /// Rays whose exact ray meets a surface, and those whose search (defaults) finds it.
    rays: usize,
    found: usize,
    /// Rays whose exact ray meets a plane first and whose 64-step search finds it; those whose
    /// one-step and linear-only hits are within a texel of the 64-step hit.
    planar: usize,
    one_step: usize,
    linear_only: usize,
    /// Rays whose exact ray meets the specular object itself first, and those whose search
    /// finds that hit (U3).
    self_rays: usize,
    self_found: usize,
    /// Secant iterations of the 64-step search, summed, and the rays, where the exact ray meets
    /// a plane and where it meets the specular object (U14).
    planar_secant: (u64, usize),
    curved_secant: (u64, usize),
}

/// Whether the search's hit `q` is the exact hit `e` of a ray from `p`: within `near` × the
/// exact distance.
fn finds(q: Option<Vec3>, p: Vec3, e: Vec3, near: f64) -> bool {
    q.is_some_and(|q| f64::from(q.distance(e)) <= near * f64::from(e.distance(p)))
}

/// [`SearchCheck`] of `scene` from its camera at `res`², in the distance map at
/// `distance-map`'s defaults.
fn search_check(scene: &Scene, res: u32, near: f64) -> crate::Result<SearchCheck> {
    use refract_core::distance_map::{SearchParams, hit};
    use refract_core::optics::{face_forward_shading_normal, reflect};
    use refract_core::{Camera, Ray};
    use refract_cpu::families::distance_map::{DistanceMap, start_layer};
    use refract_scene::SceneMesh;
    let MethodParams::DistanceMap(defaults) = dm(&[])? else {
        crate::bail!("distance-map parameters expected");
    };
    let mut map = DistanceMap::default();
    map.prepare(scene);
    map.render(scene, defaults.layers as usize, defaults.resolution)?;
    let center = map.center();
    let texel_angle = 2.0 / defaults.resolution as f32;
    let camera = scene.camera(res, res)?;
    let search = |secant_steps: u32| SearchParams {
        secant_steps,
        ..defaults.path.search
    };
    let mut check = SearchCheck::default();
    for y in 0..res {
        for x in 0..res {
            let eye_ray = camera.pixel_ray(Camera::pixel_center(x, y));
            let Some((SceneMesh::Refractor, h)) = scene.closest_hit(&eye_ray, 1e-3, None) else {
                continue;
            };
            let p = eye_ray.at(h.t);
            let n = face_forward_shading_normal(h.shading_normal, eye_ray.dir);
            let r = reflect(eye_ray.dir, n);
            let ray = Ray { origin: p, dir: r };
            let Some((mesh, exact)) = scene.closest_hit(&ray, 1e-3, None) else {
                continue;
            };
            let e = ray.at(exact.t);
            let start = Some(start_layer(SceneMesh::Refractor, p, n, center));
            let at = |steps: u32| {
                hit(&map, p - center, r, start, &search(steps))
                    .0
                    .map(|found| p + r * found.d)
            };
            let found = finds(at(defaults.path.search.secant_steps), p, e, near);
            check.rays += 1;
            check.found += usize::from(found);
            let on_plane = match mesh {
                SceneMesh::Object(k) => scene.objects[k].own_plane().is_some(),
                SceneMesh::Refractor => false,
            };
            if mesh == SceneMesh::Refractor {
                check.self_rays += 1;
                check.self_found += usize::from(found);
            }
            let (converged, work) = hit(&map, p - center, r, start, &search(64));
            let secant = if on_plane {
                Some(&mut check.planar_secant)
            } else if mesh == SceneMesh::Refractor {
                Some(&mut check.curved_secant)
            } else {
                None
            };
            if let Some((sum, rays)) = secant {
                *sum += u64::from(work.secant_steps);
                *rays += 1;
            }
            // U4 on the rays meeting a plane whose converged search finds that plane.
            let Some(converged) = converged
                .map(|found| p + r * found.d)
                .filter(|&q| on_plane && finds(Some(q), p, e, near))
            else {
                continue;
            };
            let texel = texel_angle * (converged - center).length();
            let within = |q: Option<Vec3>| q.is_some_and(|q| q.distance(converged) <= texel);
            check.planar += 1;
            check.one_step += usize::from(within(at(1)));
            check.linear_only += usize::from(within(at(0)));
        }
    }
    Ok(check)
}

/// U14: few secant iterations where the exact ray meets a plane (a mean of at most `few`), and
/// fewer than where it meets the curved specular object (both measured).
fn few_on_smooth(check: &SearchCheck, few: f64) -> bool {
    let mean = |(sum, n): (u64, usize)| (n > 0).then(|| sum as f64 / n as f64);
    matches!(
        (mean(check.planar_secant), mean(check.curved_secant)),
        (Some(smooth), Some(curved)) if smooth <= few && smooth < curved
    )
}

/// U10: FLIP at every depth 1 to 8 measured (against the reference traced to depth 8), falling
/// from depth 1 to 8 by at least `share` of `traced_gain` (the FLIP of the reference traced to
/// depth 1 against depth 8: what the ray tracer itself gains over those depths), and never
/// growing by more than `slack` from one depth to the next.
fn approaches(flips: &[Option<f64>], traced_gain: Option<f64>, share: f64, slack: f64) -> bool {
    let f: Vec<f64> = flips.iter().filter_map(|f| *f).collect();
    f.len() == 8
        && traced_gain.is_some_and(|gain| gain > 0.0 && f[0] - f[7] >= share * gain)
        && f.windows(2).all(|w| w[1] <= w[0] + slack)
}

/// U1: the search finds the exact ray's first surface on at least `share` of the rays.
fn misses_few(check: &SearchCheck, share: f64) -> bool {
    check.rays > 0 && check.found as f64 >= share * check.rays as f64
}

/// U4: one secant step is within a texel of the converged hit on at least `share` of the planar
/// rays, and more often than the linear search alone.
fn one_step_on_planes(check: &SearchCheck, share: f64) -> bool {
    check.planar > 0
        && check.one_step as f64 >= share * check.planar as f64
        && check.linear_only < check.one_step
}

/// U8: the FLIP against the reference at `own` (an index into `flips`, one per traced depth) is
/// below the FLIP against every other depth's reference (all measured).
fn closest_at_own_depth(flips: &[Option<f64>], own: usize) -> bool {
    let Some(Some(at_own)) = flips.get(own) else {
        return false;
    };
    flips
        .iter()
        .enumerate()
        .filter(|(k, _)| *k != own)
        .all(|(_, f)| f.is_some_and(|f| *at_own < f))
}

/// The room scenes: `mirror-room` (built in) and `teapot-box` with the shared data.
fn rooms(
    args: &ClaimsArgs,
    notes: &mut Vec<String>,
    progress: &dyn Progress,
) -> crate::Result<Vec<Scene>> {
    let mut scenes = vec![load_scene("mirror-room")?.scene];
    match data_scenes::load("teapot-box", &args.data, progress)? {
        Some(scene) => scenes.push(scene),
        None => {
            notes.push("teapot-box: the shared meshes are missing; its rows are skipped.".into())
        }
    }
    Ok(scenes)
}

/// Measures the claims and returns the markdown section.
pub fn section(
    args: &ClaimsArgs,
    inventory: &Inventory,
    ledger: &mut Ledger,
    progress: &dyn Progress,
) -> crate::Result<String> {
    let mut bench = Bench::new(args)?;
    let mut notes = Vec::new();
    let mut claims = vec![
        inventory.claim("U10")?,
        inventory.claim("U5")?,
        inventory.claim("U6")?,
        inventory.claim("U12")?,
    ];
    let (slack, gain_share) = (claims[0].threshold("slack")?, claims[0].threshold("share")?);
    let (bar, stated) = (
        claims[3].threshold("speedup")?,
        claims[3].threshold("repeats")?,
    );
    let repeats = args.rounds(stated);
    let mut u2 = inventory.claim("U2")?;
    let mut u7 = inventory.claim("U7")?;
    let more_layers = u7.threshold("more")?.to_string();
    let mut u9 = inventory.claim("U9")?;
    let (u9_ratio, u9_stated) = (u9.threshold("ratio")?, u9.threshold("repeats")?);
    let (fps, u2_stated) = (u2.threshold("fps")?, u2.threshold("repeats")?);
    let mut depth_tables = Vec::new();
    let mut step_tables = Vec::new();
    let mut u8 = inventory.claim("U8")?;
    let (mut u1, mut u3, mut u4) = (
        inventory.claim("U1")?,
        inventory.claim("U3")?,
        inventory.claim("U4")?,
    );
    let mut u14 = inventory.claim("U14")?;
    for scene in rooms(args, &mut notes, progress)? {
        let scene = Arc::new(scene);
        // U1 and U4: the reflected rays searched in the map against the exact rays.
        let viewed = args.view((*scene).clone());
        let check = search_check(&viewed, args.res, u1.threshold("near")?)?;
        let share = u1.threshold("share")?;
        u1.push((
            scene.name.clone(),
            misses_few(&check, share),
            format!(
                "the search finds the exact ray's first surface on {} of {} reflected rays",
                pct(Some(check.found as f64 / check.rays.max(1) as f64)),
                check.rays
            ),
        ));
        if scene.name == "teapot-box" {
            let min_rays = u3.threshold("min_rays")? as usize;
            let share = u3.threshold("share")?;
            let self_share = check.self_found as f64 / check.self_rays.max(1) as f64;
            u3.push((
                scene.name.clone(),
                if check.self_rays < min_rays {
                    Verdict::Inconclusive
                } else {
                    Verdict::from(self_share >= share)
                },
                format!(
                    "the search finds the teapot's own surface on {} of {} rays whose exact ray meets it first",
                    pct(Some(self_share)),
                    check.self_rays
                ),
            ));
            let mean = |(sum, n): (u64, usize)| sum as f64 / n.max(1) as f64;
            u14.push((
                scene.name.clone(),
                few_on_smooth(&check, u14.threshold("few")?),
                format!(
                    "mean secant iterations {:.2} on {} rays meeting a plane, {:.2} on {} rays meeting the teapot",
                    mean(check.planar_secant),
                    check.planar_secant.1,
                    mean(check.curved_secant),
                    check.curved_secant.1
                ),
            ));
        }
        u4.push((
            scene.name.clone(),
            one_step_on_planes(&check, u4.threshold("share")?),
            format!(
                "within a texel of the 64-step hit after one secant step on {} of {} rays whose exact ray meets a plane, after the linear search alone on {}",
                pct(Some(check.one_step as f64 / check.planar.max(1) as f64)),
                check.planar,
                pct(Some(check.linear_only as f64 / check.planar.max(1) as f64))
            ),
        ));
        // U8: each depth's frame against the reference traced to each depth of 1 to 4.
        let mut traced = Vec::new();
        for depth in 1..=4u32 {
            let settings = refract_scene::TraceSettings {
                max_depth: depth,
                ..refract_scene::TraceSettings::default()
            };
            traced.push(bench.truth_traced(Arc::clone(&scene), args.res, settings)?);
        }
        for depth in 1..=3usize {
            let params = dm(&[("depth", &depth.to_string())])?;
            let frame = bench.measure(&traced[depth - 1], &params)?.0;
            let flips: Vec<Option<f64>> = traced
                .iter()
                .map(|t| Bench::evaluate(t, &frame, &params).0.flip_mean)
                .collect();
            u8.push((
                format!("{}, depth {depth}", scene.name),
                closest_at_own_depth(&flips, depth - 1),
                format!(
                    "FLIP against the reference traced to depth 1 / 2 / 3 / 4: {}",
                    flips
                        .iter()
                        .map(|f| value(*f, 4))
                        .collect::<Vec<_>>()
                        .join(" / ")
                ),
            ));
        }
        let t = bench.truth_with(scene, args.res, TraceMode::Transmission)?;
        let name = t.scene.name.clone();
        let mut flips = Vec::new();
        for depth in 1..=8u32 {
            let r = bench.measure(&t, &dm(&[("depth", &depth.to_string())])?)?.1;
            flips.push((depth, r.flip_mean, r.psnr_ldr_db));
        }
        // What the ray tracer gains from depth 1 to 8: its depth-1 image against this one.
        let traced_gain = Bench::evaluate(
            &t,
            &traced[0].frame,
            &MethodParams::Reference(refract_scene::TraceSettings::default()),
        )
        .0
        .flip_mean;
        let holds = approaches(
            &flips.iter().map(|(_, f, _)| *f).collect::<Vec<_>>(),
            traced_gain,
            gain_share,
            slack,
        );
        claims[0].push((
            name.clone(),
            holds,
            format!(
                "FLIP {} (depth 1) → {} (2) → {} (3) → {} (8): a fall of {} ({} of the ray tracer's own gain from depth 1 to 8, FLIP {})",
                value(flips[0].1, 4),
                value(flips[1].1, 4),
                value(flips[2].1, 4),
                value(flips[7].1, 4),
                value(flips[0].1.zip(flips[7].1).map(|(a, b)| a - b), 4),
                pct(flips[0]
                    .1
                    .zip(flips[7].1)
                    .zip(traced_gain)
                    .map(|((a, b), g)| (a - b) / g)),
                value(traced_gain, 4)
            ),
        ));
        depth_tables.push((name.clone(), flips));

        let mut steps = Vec::new();
        for (linear, secant) in [(15, 1), (15, 10), (80, 1), (80, 10)] {
            let r = bench
                .measure(
                    &t,
                    &dm(&[
                        ("depth", "4"),
                        ("min-steps", "15"),
                        ("max-steps", &linear.to_string()),
                        ("secant", &secant.to_string()),
                    ])?,
                )?
                .1;
            steps.push(((linear, secant), r));
        }
        let flip = |k: usize| steps[k].1.flip_mean;
        claims[1].push((
            name.clone(),
            less(flip(1), flip(0)) && less(flip(3), flip(2)),
            format!(
                "FLIP 15/1 {}, 15/10 {}; 80/1 {}, 80/10 {}",
                value(flip(0), 4),
                value(flip(1), 4),
                value(flip(2), 4),
                value(flip(3), 4)
            ),
        ));
        claims[2].push((
            name.clone(),
            less(flip(2), flip(0)) && less(flip(3), flip(1)),
            format!(
                "FLIP 15/1 {} vs 80/1 {}; 15/10 {} vs 80/10 {}",
                value(flip(0), 4),
                value(flip(2), 4),
                value(flip(1), 4),
                value(flip(3), 4)
            ),
        ));
        step_tables.push((name.clone(), steps));

        // U7: more layers than the chapter's three.
        let three = bench.measure(&t, &dm(&[("depth", "4")])?)?.1;
        let more = bench
            .measure(&t, &dm(&[("depth", "4"), ("layers", &more_layers)])?)?
            .1;
        u7.push((
            name.clone(),
            less(more.flip_mean, three.flip_mean),
            format!(
                "FLIP {} (3 layers) → {} ({more_layers})",
                value(three.flip_mean, 4),
                value(more.flip_mean, 4)
            ),
        ));

        // Min-max at the chapter's setting (colour-only frames), alternating rounds.
        let camera = t.scene.camera(CHAPTER_SIZE.0, CHAPTER_SIZE.1)?;
        let configs = [
            dm(&[("minmax", "off"), ("res", "512"), ("layers", "3")])?,
            dm(&[("minmax", "on"), ("res", "512"), ("layers", "3")])?,
        ];
        let race = Race::run(&mut bench.cpu, &camera, &configs, repeats, 2, 10)?;
        // U9 on Fig. 17-7's teapot: the frame at depth 3 against depth 1, min-max on.
        if name == "teapot-box" {
            let depths = [
                dm(&[
                    ("minmax", "on"),
                    ("res", "512"),
                    ("layers", "3"),
                    ("depth", "3"),
                ])?,
                dm(&[
                    ("minmax", "on"),
                    ("res", "512"),
                    ("layers", "3"),
                    ("depth", "1"),
                ])?,
            ];
            let race = Race::run(
                &mut bench.cpu,
                &camera,
                &depths,
                args.rounds(u9_stated),
                2,
                10,
            )?;
            let ratios = race.ratios();
            let (lo, mid, hi) = spread(&ratios).unwrap_or_default();
            let (deep_ms, one_ms) = race.mean_ms();
            u9.push((
                name.clone(),
                args.timing_verdict(
                    u9_stated,
                    &at_most_ratio(&ratios, u9_ratio),
                ),
                format!(
                    "CPU ({}): {one_ms:.1} ms at depth 1, {deep_ms:.1} ms at depth 3 (means of the rounds' medians); ratio median {mid:.2}×, range {lo:.2}–{hi:.2}× over {} alternating rounds",
                    crate::timing::cpu_description(),
                    ratios.len()
                ),
            ));
        }
        let min_max_ms: Vec<f64> = race.medians.iter().map(|m| m.1).collect();
        u2.push((
            name.clone(),
            args.timing_verdict(u2_stated, &at_frame_rate(&min_max_ms, fps)),
            format!(
                "CPU ({}), min-max: {} fps (the rounds' medians: {} ms; paper: 50 fps, GeForce 8800 GTX)",
                crate::timing::cpu_description(),
                fps_range(&min_max_ms),
                min_max_ms
                    .iter()
                    .map(|ms| format!("{ms:.1}"))
                    .collect::<Vec<_>>()
                    .join(", "),
            ),
        ));
        let speedups = race.ratios();
        let (lo, mid, hi) = spread(&speedups).unwrap_or_default();
        let (off_ms, on_ms) = race.mean_ms();
        claims[3].push((
            name.clone(),
            args.timing_verdict(
                stated,
                &speedups.iter().map(|&x| x >= bar).collect::<Vec<_>>(),
            ),
            format!(
                "CPU ({}): {off_ms:.1} ms without, {on_ms:.1} ms with min-max (means of the rounds' medians); speed-up median {mid:.2}×, range {lo:.2}–{hi:.2}× over {} alternating rounds of 10 frames (paper: 2×, GeForce 8800 GTX)",
                crate::timing::cpu_description(),
                speedups.len()
            ),
        ));
    }

    // Fig. 17-9: the glass sphere that reflects and refracts, against the full reference.
    let glass = Arc::new(load_scene("glass-room")?.scene);
    let full = bench.truth_with(Arc::clone(&glass), args.res, TraceMode::Full)?;
    let transmission = bench.truth_with(glass, args.res, TraceMode::Transmission)?;
    let split = bench
        .measure(&full, &dm(&[("depth", "4"), ("fresnel", "split")])?)?
        .1;
    let none_vs_full = bench.measure(&full, &dm(&[("depth", "4")])?)?.1;
    let none = bench.measure(&transmission, &dm(&[("depth", "4")])?)?.1;
    // The bar: the exact image without reflection (the reference's `transmission` mode).
    let exact_unreflected = Bench::evaluate(
        &full,
        &transmission.frame,
        &MethodParams::Reference(refract_scene::TraceSettings::default()),
    )
    .0;
    let mut u13 = inventory.claim("U13")?;
    u13.push((
        "glass-room".into(),
        less(split.flip_mean, exact_unreflected.flip_mean),
        format!(
            "FLIP vs `full`: {} (split) vs {} (the reference's exact `transmission` image; `distance-map` without the split: {}); `none` vs `transmission`: {}",
            value(split.flip_mean, 4),
            value(exact_unreflected.flip_mean, 4),
            value(none_vs_full.flip_mean, 4),
            value(none.flip_mean, 4)
        ),
    ));
    claims.push(u13);
    claims.extend([u1, u3, u4, u8, u14]);
    claims.extend([u2, u7, u9]);

    // The two families on the same frames: glass in a pure environment.
    let mut versus = Vec::new();
    let mut glass_scenes = vec![load_scene("sphere")?.scene, load_scene("torus")?.scene];
    glass_scenes.push(load_scene("lens")?.scene);
    for scene in glass_scenes {
        let t = bench.truth_with(Arc::new(scene), args.res, TraceMode::Transmission)?;
        let wyman = bench
            .measure(&t, &MethodParams::defaults(MethodId::Wyman))?
            .1;
        let d2 = bench.measure(&t, &dm(&[])?)?.1;
        let d8 = bench.measure(&t, &dm(&[("depth", "8")])?)?.1;
        versus.push((t.scene.name.clone(), wyman, d2, d8));
    }
    let mut b1 = inventory.claim("B1")?;
    for (name, w, _, d8) in &versus {
        b1.push((
            name.clone(),
            less(d8.flip_mean, w.flip_mean),
            format!(
                "FLIP {} (`distance-map`, depth 8) vs {} (`wyman`)",
                value(d8.flip_mean, 4),
                value(w.flip_mean, 4)
            ),
        ));
    }
    claims.push(b1);

    let heading = "Umenhoffer et al. 2007 (GPU Gems 3 ch. 17, `distance-map`)";
    let mut md = format!(
        "\n## {heading}\n\n\
         CPU backend at {res}² unless noted, against the reference (transmission mode: glass \
         refracts without Fresnel weights, conductors reflect with their exact Fresnel \
         reflectance; depth 8). Default parameters: 3 layers of 6 × 512², 15–80 linear and 5 \
         secant steps, min-max on.\n\n\
         | claim | scene | measured | verdict |\n|---|---|---|---|\n",
        res = args.res
    );
    ledger.rows(&mut md, heading, &claims);
    for note in &notes {
        let _ = writeln!(md, "\n{note}");
    }
    for (name, flips) in &depth_tables {
        let _ = writeln!(
            md,
            "\n### Error vs maximum depth (Fig. 17-8), {name}\n\n| depth | FLIP | PSNR (dB) |\n|---|---|---|"
        );
        for (depth, flip, psnr) in flips {
            let _ = writeln!(
                md,
                "| {depth} | {} | {} |",
                value(*flip, 4),
                value(*psnr, 2)
            );
        }
    }
    for (name, steps) in &step_tables {
        let _ = writeln!(
            md,
            "\n### Linear/secant steps (Fig. 17-6), {name}, depth 4\n\n| linear/secant | FLIP | PSNR (dB) | linear samples / pixel | secant steps / pixel |\n|---|---|---|---|---|"
        );
        for ((linear, secant), r) in steps {
            let _ = writeln!(
                md,
                "| {linear}/{secant} | {} | {} | {} | {} |",
                value(r.flip_mean, 4),
                value(r.psnr_ldr_db, 2),
                value(r.linear_steps_mean, 1),
                value(r.secant_steps_mean, 2)
            );
        }
    }
    let _ = writeln!(
        md,
        "\n### `distance-map` vs `wyman`, glass in the procedural environment\n\n| scene | `wyman` FLIP | `distance-map` depth 2 | depth 8 |\n|---|---|---|---|"
    );
    for (name, w, d2, d8) in &versus {
        let _ = writeln!(
            md,
            "| {name} | {} | {} | {} |",
            value(w.flip_mean, 4),
            value(d2.flip_mean, 4),
            value(d8.flip_mean, 4)
        );
    }
    let _ = writeln!(
        md,
        "\nFrame rates at the chapter's setting on both backends are in `refract bench --table \
         distance-map` (`docs/performance.md`)."
    );
    Ok(md)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// U10 fails on a FLIP that grows by more than the slack, on a fall short of half the ray
    /// tracer's gain (a map whose deeper bounces find little), and on a depth or gain not
    /// measured.
    #[test]
    fn u10_verdict_can_fail() {
        let f = |v: &[f64]| v.iter().map(|&x| Some(x)).collect::<Vec<_>>();
        let falling = [0.2, 0.1, 0.08, 0.07, 0.065, 0.06, 0.06, 0.059];
        let u10 = |flips: &[Option<f64>], gain| approaches(flips, gain, 0.5, 0.002);
        // A fall of 0.141 against a gain of 0.2: 70 %.
        assert!(u10(&f(&falling), Some(0.2)));
        // The same fall against a gain of 0.3: 47 %.
        assert!(!u10(&f(&falling), Some(0.3)));
        let mut bump = falling;
        bump[4] = 0.075;
        assert!(!u10(&f(&bump), Some(0.2)));
        assert!(!u10(&f(&[0.1; 8]), Some(0.2)));
        let mut missing = f(&falling);
        missing[3] = None;
        assert!(!u10(&missing, Some(0.2)));
        assert!(!u10(&f(&falling), None));
        assert!(!u10(&f(&falling), Some(0.0)));
    }

    /// U1, U4 and U14 fail on a search that misses, on a one-step hit off the converged one, and
    /// where the linear search alone does as well (the secant step would show nothing).
    #[test]
    fn search_verdicts_can_fail() {
        let c = |rays, found, planar, one_step, linear_only| SearchCheck {
            rays,
            found,
            planar,
            one_step,
            linear_only,
            ..SearchCheck::default()
        };
        let smooth = |planar_secant, curved_secant| SearchCheck {
            planar_secant,
            curved_secant,
            ..SearchCheck::default()
        };
        assert!(few_on_smooth(&smooth((120, 100), (400, 100)), 3.0));
        assert!(!few_on_smooth(&smooth((350, 100), (400, 100)), 3.0));
        assert!(!few_on_smooth(&smooth((120, 100), (100, 100)), 3.0));
        assert!(!few_on_smooth(&smooth((120, 100), (0, 0)), 3.0));
        assert!(misses_few(&c(1000, 995, 0, 0, 0), 0.99));
        assert!(!misses_few(&c(1000, 980, 0, 0, 0), 0.99));
        assert!(!misses_few(&c(0, 0, 0, 0, 0), 0.99));
        assert!(one_step_on_planes(&c(100, 100, 100, 96, 40), 0.95));
        assert!(!one_step_on_planes(&c(100, 100, 100, 90, 40), 0.95));
        assert!(!one_step_on_planes(&c(100, 100, 100, 97, 97), 0.95));
        assert!(!one_step_on_planes(&c(100, 100, 0, 0, 0), 0.95));
        let (p, e) = (Vec3::ZERO, Vec3::new(10.0, 0.0, 0.0));
        assert!(finds(Some(Vec3::new(10.4, 0.0, 0.0)), p, e, 0.05));
        assert!(!finds(Some(Vec3::new(10.6, 0.0, 0.0)), p, e, 0.05));
        assert!(!finds(None, p, e, 0.05));
    }

    /// U8 fails where the frame is as close to another depth's reference (or closer), or a
    /// FLIP is missing, and holds where its own depth is strictly closest.
    #[test]
    fn u8_verdict_can_fail() {
        let f = |v: &[f64]| v.iter().map(|&x| Some(x)).collect::<Vec<_>>();
        assert!(closest_at_own_depth(&f(&[0.05, 0.2, 0.25, 0.3]), 0));
        assert!(!closest_at_own_depth(&f(&[0.05, 0.04, 0.25, 0.3]), 0));
        assert!(!closest_at_own_depth(&f(&[0.2, 0.1, 0.1, 0.3]), 1));
        assert!(!closest_at_own_depth(&[Some(0.05), None, Some(0.3)], 0));
        assert!(!closest_at_own_depth(&[None, Some(0.2)], 0));
    }

    /// U2 on rounds of known times: all under 40 ms confirm 25 fps, all over refute it, and
    /// rounds on both sides (or too few) are inconclusive.
    #[test]
    fn u2_verdict_can_fail() {
        let args = ClaimsArgs {
            res: 64,
            data: "data".into(),
            out: "claims.md".into(),
            timing_rounds: None,
            reference_backend: Default::default(),
            second_res: None,
            orbit_deg: 0.0,
        };
        let verdict = |ms: &[f64]| args.timing_verdict(5.0, &at_frame_rate(ms, 25.0));
        assert_eq!(verdict(&[30.0, 35.0, 39.9, 38.0, 20.0]), Verdict::Confirmed);
        assert_eq!(
            verdict(&[49.0, 48.8, 50.1, 47.0, 41.0]),
            Verdict::NotConfirmed
        );
        assert_eq!(
            verdict(&[39.0, 41.0, 39.0, 39.0, 39.0]),
            Verdict::Inconclusive
        );
        assert_eq!(verdict(&[30.0, 30.0]), Verdict::Inconclusive);
        assert_eq!(fps_range(&[40.0, 50.0, 20.0]), "20.0–50.0");
        // U9: "decreases very little" within 1.25 ×.
        let u9 = |r: &[f64]| args.timing_verdict(5.0, &at_most_ratio(r, 1.25));
        assert_eq!(u9(&[1.1, 1.2, 1.0, 1.24, 1.1]), Verdict::Confirmed);
        assert_eq!(u9(&[1.6, 1.8, 1.7, 1.5, 1.9]), Verdict::NotConfirmed);
        assert_eq!(u9(&[1.2, 1.3, 1.2, 1.2, 1.2]), Verdict::Inconclusive);
    }
}
