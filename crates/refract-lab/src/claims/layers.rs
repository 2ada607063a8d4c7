//! The glass-behind-glass section of `docs/claims.md` (issue 49): on the many-refractor scenes
//! (`glass-behind-glass`, `vessel`, `liquid`), the share of refractor pixels whose exact path
//! crosses more than two interfaces, every method's FLIP over all its pixels and over those,
//! what each method shows on those pixels (the environment, the right object, a wrong one),
//! `depth-peel` at 1, 2, 4 and 8 layers, and claims B5, B6 and B7. All on the CPU backend
//! against the reference in transmission mode.

use std::fmt::Write as _;
use std::sync::Arc;

use glam::Vec3;
use refract_eval::load_scene;
use refract_scene::{Aov, Family, Frame, MethodId, MethodParams, REGISTRY, TraceMode};

use super::inventory::{Inventory, Ledger, Verdict};
use super::{Bench, ClaimsArgs, pct, value};

/// The scenes of the section.
const SCENES: [&str; 3] = ["glass-behind-glass", "vessel", "liquid"];

/// The methods B5 is stated for.
const B5_METHODS: [MethodId; 2] = [MethodId::Wyman, MethodId::VolumeThickness];

/// The layer counts of `depth-peel` measured (B7).
const LAYERS: [u32; 4] = [1, 2, 4, 8];

/// A method's opaque hit is the reference's where the two are within this distance, in scene
/// units (the scenes' refractors have radii 0.5 to 0.8).
const RIGHT_OBJECT_TOLERANCE: f32 = 0.05;

/// What a method shows on a set of pixels, against the reference: the environment, the
/// reference's object point, another object point.
#[derive(Clone, Copy, Debug, Default)]
struct Shown {
    pixels: usize,
    environment: usize,
    right: usize,
    wrong: usize,
}

impl Shown {
    /// Pixel by pixel where `keep` holds: `P_geom` of the method (none: it shows the
    /// environment) against the reference's.
    fn of(method: &Frame, truth: &Frame, keep: impl Fn(usize) -> bool) -> Self {
        let none = vec![Vec3::NAN; truth.pixel_count()];
        let ours = method.vec3(Aov::PGeom).unwrap_or(&none);
        let exact = truth.vec3(Aov::PGeom).unwrap_or(&none);
        let mut shown = Self::default();
        for i in (0..truth.pixel_count()).filter(|&i| keep(i)) {
            shown.pixels += 1;
            if ours[i].is_nan() {
                shown.environment += 1;
            } else if (ours[i] - exact[i]).length() <= RIGHT_OBJECT_TOLERANCE {
                shown.right += 1;
            } else {
                shown.wrong += 1;
            }
        }
        shown
    }

    fn share(&self, n: usize) -> String {
        pct((self.pixels > 0).then(|| n as f64 / self.pixels as f64))
    }
}

/// The mean of `flip` over the pixels `keep` selects, and their number.
fn mean_over(flip: &[f32], keep: impl Fn(usize) -> bool) -> (Option<f64>, usize) {
    let (sum, n) = (0..flip.len())
        .filter(|&i| keep(i) && flip[i].is_finite())
        .fold((0.0, 0usize), |(s, n), i| (s + f64::from(flip[i]), n + 1));
    ((n > 0).then(|| sum / n as f64), n)
}

/// One method on one scene: FLIP over the reference's refractor pixels, and over the pixels the
/// method draws split by the reference path's interface count (two or fewer, more).
struct Row {
    method: &'static str,
    flip: Option<f64>,
    drawn_few: (Option<f64>, usize),
    drawn_many: (Option<f64>, usize),
}

pub fn section(
    args: &ClaimsArgs,
    inventory: &Inventory,
    ledger: &mut Ledger,
) -> crate::Result<String> {
    let mut bench = Bench::new(args)?;
    let mut b5 = inventory.claim("B5")?;
    let ratio = b5.threshold("ratio")?;
    let min_pixels = b5.threshold("min_pixels")? as usize;
    let mut b6 = inventory.claim("B6")?;
    let b6_ratio = b6.threshold("ratio")?;
    let mut b7 = inventory.claim("B7")?;
    let tolerance = b7.threshold("tolerance")?;
    let mut tables = String::new();
    let mut shares = Vec::new();
    let mut shown_rows = String::new();
    let mut layer_rows = String::new();
    for name in SCENES {
        let scene = load_scene(name)?.scene;
        let truth = bench.truth_with(Arc::new(scene), args.res, TraceMode::Transmission)?;
        let covered = truth
            .frame
            .flag(Aov::Covered)
            .ok_or_else(|| crate::LabError::invalid("the reference wrote no coverage"))?
            .to_vec();
        let interfaces = truth
            .frame
            .count(Aov::Interfaces)
            .ok_or_else(|| crate::LabError::invalid("the reference wrote no interface count"))?
            .to_vec();
        let refractor_pixels = covered.iter().filter(|c| **c).count();
        let many = |i: usize| covered[i] && interfaces[i] > 2;
        let many_pixels = (0..covered.len()).filter(|&i| many(i)).count();
        shares.push((
            name,
            refractor_pixels,
            many_pixels as f64 / refractor_pixels.max(1) as f64,
        ));
        let mut rows = Vec::new();
        for info in REGISTRY.iter().filter(|m| {
            m.family != Family::Reference && m.backends.contains(&refract_scene::BackendId::Cpu)
        }) {
            let params = MethodParams::defaults(info.id);
            let (frame, _, maps) = bench.measure_maps(&truth, &params)?;
            let drawn = frame
                .flag(Aov::Covered)
                .map(<[bool]>::to_vec)
                .unwrap_or_default();
            let draws = |i: usize| drawn.get(i).copied().unwrap_or(false) && covered[i];
            let row = Row {
                method: info.name,
                flip: mean_over(&maps.flip, |i| covered[i]).0,
                drawn_few: mean_over(&maps.flip, |i| draws(i) && interfaces[i] <= 2),
                drawn_many: mean_over(&maps.flip, |i| draws(i) && interfaces[i] > 2),
            };
            if B5_METHODS.contains(&info.id) {
                let (few, many) = (row.drawn_few, row.drawn_many);
                let verdict = match (few, many) {
                    ((Some(f), nf), (Some(m), nm)) if nf >= min_pixels && nm >= min_pixels => {
                        Verdict::from(m >= ratio * f)
                    }
                    _ => Verdict::Inconclusive,
                };
                b5.push((
                    format!("{name}, `{}`", info.name),
                    verdict,
                    format!(
                        "FLIP {} on {} pixels of > 2 interfaces vs {} on {} of ≤ 2",
                        value(many.0, 4),
                        many.1,
                        value(few.0, 4),
                        few.1
                    ),
                ));
            }
            let shown = Shown::of(&frame, &truth.frame, |i| many(i) && draws(i));
            let _ = writeln!(
                shown_rows,
                "| {name} | `{}` | {} | {} | {} | {} |",
                info.name,
                shown.pixels,
                shown.share(shown.environment),
                shown.share(shown.right),
                shown.share(shown.wrong)
            );
            rows.push(row);
        }
        let reference = Shown::of(&truth.frame, &truth.frame, many);
        let _ = writeln!(
            shown_rows,
            "| {name} | reference | {} | {} | {} | – |",
            reference.pixels,
            reference.share(reference.environment),
            reference.share(reference.right),
        );
        // B6: depth-peel at its defaults against the best of the others.
        let peel = rows.iter().find(|r| r.method == MethodId::DepthPeel.name());
        let best = rows
            .iter()
            .filter(|r| r.method != MethodId::DepthPeel.name())
            .filter_map(|r| r.flip.map(|f| (f, r.method)))
            .min_by(|a, b| a.0.total_cmp(&b.0));
        let verdict = match (peel.and_then(|p| p.flip), best) {
            (Some(p), Some((b, _))) => Verdict::from(p <= b6_ratio * b),
            _ => Verdict::Inconclusive,
        };
        b6.push((
            name.to_owned(),
            verdict,
            format!(
                "`depth-peel` FLIP {} vs best other `{}` {}",
                value(peel.and_then(|p| p.flip), 4),
                best.map_or("–", |b| b.1),
                value(best.map(|b| b.0), 4)
            ),
        ));
        // B7 and the layer table: depth-peel at 1, 2, 4, 8 layers.
        let exact_interfaces = &interfaces;
        let mut flips = Vec::new();
        for layers in LAYERS {
            let mut params = MethodParams::defaults(MethodId::DepthPeel);
            params.set("layers", &layers.to_string(), "claims")?;
            let (frame, _, maps) = bench.measure_maps(&truth, &params)?;
            let flip = mean_over(&maps.flip, |i| covered[i]).0;
            flips.push(flip);
            let drawn = frame
                .flag(Aov::Covered)
                .map(<[bool]>::to_vec)
                .unwrap_or_default();
            let ours = frame
                .count(Aov::Interfaces)
                .map(<[u32]>::to_vec)
                .unwrap_or_default();
            let lost = frame
                .flag(Aov::Miss)
                .map(<[bool]>::to_vec)
                .unwrap_or_default();
            let in_both: Vec<bool> = (0..covered.len())
                .map(|i| covered[i] && drawn.get(i).copied().unwrap_or(false))
                .collect();
            let both: Vec<usize> = (0..covered.len()).filter(|&i| in_both[i]).collect();
            let share = |f: &dyn Fn(usize) -> bool| {
                (!both.is_empty())
                    .then(|| both.iter().filter(|&&i| f(i)).count() as f64 / both.len() as f64)
            };
            let shown = Shown::of(&frame, &truth.frame, |i| many(i) && in_both[i]);
            let _ = writeln!(
                layer_rows,
                "| {name} | {layers} | {} | {} | {} | {} |",
                value(flip, 4),
                pct(share(&|i| ours.get(i) == exact_interfaces.get(i))),
                pct(share(&|i| lost.get(i).copied().unwrap_or(false))),
                shown.share(shown.right),
            );
        }
        let steps_hold = flips
            .windows(2)
            .map(|w| match (w[0], w[1]) {
                (Some(a), Some(b)) => Some(b <= a + tolerance),
                _ => None,
            })
            .collect::<Option<Vec<bool>>>();
        b7.push((
            name.to_owned(),
            steps_hold.map_or(Verdict::Inconclusive, |s| {
                Verdict::from(s.iter().all(|h| *h))
            }),
            format!(
                "FLIP at {} layers: {}",
                LAYERS.map(|l| l.to_string()).join(", "),
                flips
                    .iter()
                    .map(|f| value(*f, 4))
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        ));
        let _ = writeln!(
            tables,
            "\n### {name}\n\n| method | FLIP (reference's glass) | FLIP where drawn, ≤ 2 interfaces (pixels) | FLIP where drawn, > 2 interfaces (pixels) |\n|---|---|---|---|"
        );
        for r in &rows {
            let _ = writeln!(
                tables,
                "| `{}` | {} | {} ({}) | {} ({}) |",
                r.method,
                value(r.flip, 4),
                value(r.drawn_few.0, 4),
                r.drawn_few.1,
                value(r.drawn_many.0, 4),
                r.drawn_many.1
            );
        }
    }
    let heading = "Glass behind glass (issue 49)";
    let mut md = format!(
        "\n## {heading}\n\n\
         CPU backend at {res}², against the reference in transmission mode, which follows the \
         ray through every refractor (`docs/reference.md`). `depth-peel` follows it through \
         the refractors' peeled surfaces; every other method follows one refractor through at \
         most two interfaces (`docs/methods.md`, \"Several refractors\"). \
         \"Interfaces\" are the refractions on the reference's path (`interfaces` AOV).\n\n\
         | scene | refractor pixels | share whose path crosses > 2 interfaces |\n|---|---|---|\n",
        res = args.res
    );
    for (name, pixels, share) in &shares {
        let _ = writeln!(md, "| {name} | {pixels} | {} |", pct(Some(*share)));
    }
    md.push_str("\n| claim | scene | measured | verdict |\n|---|---|---|---|\n");
    ledger.rows(&mut md, heading, &[b5, b6, b7]);
    let _ = write!(
        md,
        "\n### What each method shows where the exact path crosses more than two interfaces\n\n\
         Over the reference's refractor pixels whose path crosses more than two interfaces and \
         that the method draws: the share where the method shows the environment (no object \
         hit), the object point the reference's path ends on (its `P_geom` within \
         {RIGHT_OBJECT_TOLERANCE} scene units of the reference's), or another object point. \
         The reference's own row: where its path ends in the environment, and on an object.\n\n\
         | scene | method | pixels | environment | right object | wrong object |\n\
         |---|---|---|---|---|---|\n{shown_rows}"
    );
    let _ = write!(
        md,
        "\n### `depth-peel` at 1, 2, 4 and 8 layers\n\n\
         Mean FLIP over the reference's refractor pixels; over the pixels both draw, the share \
         whose path crosses as many interfaces as the reference's and the share lost inside a \
         medium (`miss`); over those crossing more than two interfaces, the share ending on the \
         reference's object point.\n\n\
         | scene | layers | FLIP | same interface count | lost inside | right object (> 2 interfaces) |\n\
         |---|---|---|---|---|---|\n{layer_rows}"
    );
    md.push_str(&tables);
    Ok(md)
}
