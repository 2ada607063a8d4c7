//! The glass-behind-glass section of `docs/claims.md` (issue 49): on the many-refractor scenes
//! (`glass-behind-glass`, `vessel`, `liquid`), the share of refractor pixels whose exact path
//! crosses more than two interfaces, every method's FLIP over all its pixels and over those,
//! and claim B5. All on the CPU backend against the reference in transmission mode.

use std::fmt::Write as _;
use std::sync::Arc;

use refract_eval::load_scene;
use refract_scene::{Aov, Family, MethodId, MethodParams, REGISTRY, TraceMode};

use super::inventory::{Inventory, Ledger, Verdict};
use super::{Bench, ClaimsArgs, pct, value};

/// The scenes of the section.
const SCENES: [&str; 3] = ["glass-behind-glass", "vessel", "liquid"];

/// The methods B5 is stated for.
const B5_METHODS: [MethodId; 2] = [MethodId::Wyman, MethodId::VolumeThickness];

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
    let mut tables = String::new();
    let mut shares = Vec::new();
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
            rows.push(row);
        }
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
         ray through every refractor (`docs/reference.md`). Every other method follows one \
         refractor through at most two interfaces (`docs/methods.md`, \"Several refractors\"). \
         \"Interfaces\" are the refractions on the reference's path (`interfaces` AOV).\n\n\
         | scene | refractor pixels | share whose path crosses > 2 interfaces |\n|---|---|---|\n",
        res = args.res
    );
    for (name, pixels, share) in &shares {
        let _ = writeln!(md, "| {name} | {pixels} | {} |", pct(Some(*share)));
    }
    md.push_str("\n| claim | scene | measured | verdict |\n|---|---|---|---|\n");
    ledger.rows(&mut md, heading, &[b5]);
    md.push_str(&tables);
    Ok(md)
}
