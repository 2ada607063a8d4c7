//! The claims as data (`crates/refract-lab/claims.toml`): every claim of the four papers'
//! inventory (`../shared/paper-claims.md`: W1-W13, N1-N16, U1-U14, K1-K21) with its test and
//! thresholds stated before measuring, or the reason it is not measured here; the claims beyond
//! the papers (B*); and the revisions of a test after it was measured. The sections of `refract
//! claims` take each claim's words and thresholds from here, compute verdicts ([`Verdict`]) and
//! record them in a [`Ledger`], from which the coverage table (one row per claim) is written.

use std::collections::BTreeMap;
use std::fmt::Write as _;

use serde::Deserialize;

use super::history::{History, Order};

/// The claims file, compiled in.
const CLAIMS_TOML: &str = include_str!("../../claims.toml");

/// The inventory's claim ids, in the papers' order: the ids the file must hold, each once.
pub(crate) fn inventory_ids() -> Vec<String> {
    [("W", 13), ("N", 16), ("U", 14), ("K", 21)]
        .iter()
        .flat_map(|&(p, n)| (1..=n).map(move |k| format!("{p}{k}")))
        .collect()
}

/// One claim of the file.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct ClaimSpec {
    pub id: String,
    /// The paper's words (a summary; the section is the authority).
    pub words: String,
    pub section: String,
    /// How it is tested here, with `{name}` for each threshold.
    pub test: Option<String>,
    /// When the test was first stated.
    pub stated: Option<String>,
    /// The numbers the verdict compares with.
    #[serde(default)]
    pub thresholds: BTreeMap<String, f64>,
    /// Why no verdict is given here.
    pub not_measured: Option<String>,
}

/// A test changed after it was measured.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct Revision {
    pub date: String,
    pub id: String,
    pub before: String,
    pub after: String,
    pub reason: String,
}

/// The claims file.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct Inventory {
    #[serde(rename = "claim")]
    pub claims: Vec<ClaimSpec>,
    #[serde(rename = "revision", default)]
    pub revisions: Vec<Revision>,
}

impl Inventory {
    /// The compiled-in `claims.toml`, checked ([`Self::parse`]).
    pub fn builtin() -> crate::Result<Self> {
        Self::parse(CLAIMS_TOML)
    }

    /// Parses and checks a claims file: every inventory id once, each claim either tested
    /// (with a date, and every `{name}` of its test a threshold) or not measured with a
    /// reason, and every revision about a claim of the file.
    pub fn parse(text: &str) -> crate::Result<Self> {
        let inventory: Self = toml::from_str(text)
            .map_err(|e| crate::LabError::invalid(format_args!("claims.toml: {e}")))?;
        let invalid = |id: &str, what: &str| {
            crate::LabError::invalid(format_args!("claims.toml: claim {id}: {what}"))
        };
        for id in inventory_ids() {
            let n = inventory.claims.iter().filter(|c| c.id == id).count();
            crate::ensure!(
                n == 1,
                "claims.toml: claim {id} appears {n} times, expected once"
            );
        }
        for c in &inventory.claims {
            match (&c.test, &c.not_measured) {
                (Some(test), None) => {
                    if c.stated.is_none() {
                        return Err(invalid(&c.id, "a test without the date it was stated"));
                    }
                    for name in placeholders(test) {
                        if !c.thresholds.contains_key(&name) {
                            return Err(invalid(&c.id, &format!("{{{name}}} is not a threshold")));
                        }
                    }
                }
                (None, Some(_)) => {}
                _ => {
                    return Err(invalid(
                        &c.id,
                        "expected either `test` or `not_measured`, not both or neither",
                    ));
                }
            }
        }
        for r in &inventory.revisions {
            if !inventory.claims.iter().any(|c| c.id == r.id) {
                return Err(invalid(
                    &r.id,
                    "a revision of a claim the file does not hold",
                ));
            }
        }
        Ok(inventory)
    }

    /// The tested claim `id`, ready to take rows.
    pub fn claim(&self, id: &'static str) -> crate::Result<Claim> {
        let spec =
            self.claims.iter().find(|c| c.id == id).ok_or_else(|| {
                crate::LabError::invalid(format_args!("claims.toml: no claim {id}"))
            })?;
        let text = row_text(spec).ok_or_else(|| {
            crate::LabError::invalid(format_args!("claims.toml: claim {id} is not measured"))
        })?;
        Ok(Claim {
            id,
            text,
            thresholds: spec.thresholds.clone(),
            rows: Vec::new(),
        })
    }
}

/// The text a tested claim's rows open with: its id, the paper's words, the section and the
/// test with its thresholds filled in; `None` for a claim without a test.
pub(crate) fn row_text(spec: &ClaimSpec) -> Option<String> {
    let test = spec.test.as_deref()?;
    Some(format!(
        "**{}** {} ({}): {}",
        spec.id,
        spec.words,
        spec.section,
        fill(test, &spec.thresholds)
    ))
}

/// The `{name}`s of a test.
fn placeholders(test: &str) -> Vec<String> {
    test.split('{')
        .skip(1)
        .filter_map(|rest| rest.split_once('}').map(|(name, _)| name.to_owned()))
        .collect()
}

/// `test` with each `{name}` replaced by its threshold.
fn fill(test: &str, thresholds: &BTreeMap<String, f64>) -> String {
    let mut out = test.to_owned();
    for (name, value) in thresholds {
        out = out.replace(&format!("{{{name}}}"), &value.to_string());
    }
    out
}

/// What a row's measurement says about its claim.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Verdict {
    Confirmed,
    NotConfirmed,
    /// Repeated measurements fall on both sides of the threshold (timing).
    Inconclusive,
    /// Confirmed at one resolution and not at the robustness pass's, or the other way round
    /// ([`Ledger::with_second`]): neither is published.
    Fragile,
}

impl From<bool> for Verdict {
    fn from(holds: bool) -> Self {
        if holds {
            Self::Confirmed
        } else {
            Self::NotConfirmed
        }
    }
}

impl Verdict {
    /// The verdict of repeated measurements each of which holds or not: all hold, none holds,
    /// or inconclusive.
    pub fn of_repeats(holds: impl IntoIterator<Item = bool>) -> Self {
        let (mut yes, mut no) = (0, 0);
        for h in holds {
            if h {
                yes += 1;
            } else {
                no += 1;
            }
        }
        match (yes, no) {
            (0, 0) => Self::Inconclusive,
            (_, 0) => Self::Confirmed,
            (0, _) => Self::NotConfirmed,
            _ => Self::Inconclusive,
        }
    }

    /// The verdict as a plain word.
    fn word(self) -> &'static str {
        match self {
            Self::Confirmed => "confirmed",
            Self::NotConfirmed => "not confirmed",
            Self::Inconclusive => "inconclusive",
            Self::Fragile => "fragile",
        }
    }

    fn markdown(self) -> &'static str {
        match self {
            Self::Confirmed => "**confirmed**",
            Self::NotConfirmed => "**not confirmed**",
            Self::Inconclusive => "**inconclusive**",
            Self::Fragile => "**fragile**",
        }
    }
}

/// A tested claim: its text (id, the paper's words, the test with its thresholds) and its rows,
/// one per scene: the verdict and the numbers that give it.
pub(crate) struct Claim {
    pub id: &'static str,
    pub text: String,
    thresholds: BTreeMap<String, f64>,
    pub rows: Vec<(String, Verdict, String)>,
}

impl Claim {
    /// Threshold `name` of the claim (`claims.toml`); a missing one is an error naming it.
    pub fn threshold(&self, name: &str) -> crate::Result<f64> {
        self.thresholds.get(name).copied().ok_or_else(|| {
            crate::LabError::invalid(format_args!(
                "claims.toml: claim {} has no threshold `{name}`",
                self.id
            ))
        })
    }

    /// A row: the scene, whether the claim holds there (or its [`Verdict`]), the numbers.
    pub fn push(&mut self, (scene, verdict, numbers): (String, impl Into<Verdict>, String)) {
        self.rows.push((scene, verdict.into(), numbers));
    }
}

/// Every verdict given, by claim id, for the coverage table.
#[derive(Default)]
pub(crate) struct Ledger {
    verdicts: BTreeMap<String, Vec<(String, Verdict)>>,
    /// The section each claim's rows are in.
    sections: BTreeMap<String, String>,
    /// The robustness pass: how it measured (resolution, camera) and its rows.
    second: Option<(String, MeasuredRows)>,
    /// The rows as measured, for a later pass to compare with.
    measured: MeasuredRows,
}

/// Per claim id, its rows as measured: scene, verdict, numbers.
type MeasuredRows = BTreeMap<String, Vec<(String, Verdict, String)>>;

impl Ledger {
    /// Writes the markdown rows of `claims` into `md` and records their verdicts under
    /// `section` (the heading the rows are under).
    pub fn rows(&mut self, md: &mut String, section: &str, claims: &[Claim]) {
        for claim in claims {
            for (scene, verdict, numbers) in &claim.rows {
                self.measured.entry(claim.id.to_owned()).or_default().push((
                    scene.clone(),
                    *verdict,
                    numbers.clone(),
                ));
                let (verdict, numbers) = self.robust(claim.id, scene, *verdict, numbers);
                let _ = writeln!(
                    md,
                    "| {} | {scene} | {numbers} | {} |",
                    claim.text,
                    verdict.markdown()
                );
                self.verdicts
                    .entry(claim.id.to_owned())
                    .or_default()
                    .push((scene.clone(), verdict));
            }
            self.sections
                .entry(claim.id.to_owned())
                .or_insert_with(|| section.to_owned());
        }
    }

    /// A ledger whose rows are compared with `second`'s, measured as `how` says (for example
    /// "384², camera turned 5°"): a row of the same claim and scene that is confirmed in one
    /// and not confirmed in the other becomes [`Verdict::Fragile`], with both measurements.
    pub fn with_second(how: String, second: Ledger) -> Self {
        Self {
            second: Some((how, second.measured)),
            ..Self::default()
        }
    }

    /// The verdict and numbers a row is published with: as measured, or fragile where the
    /// robustness pass's row of the same claim and scene came out the other way (an
    /// inconclusive or missing row there changes nothing).
    fn robust(&self, id: &str, scene: &str, verdict: Verdict, numbers: &str) -> (Verdict, String) {
        let other = self.second.as_ref().and_then(|(how, rows)| {
            rows.get(id)?
                .iter()
                .find(|(s, _, _)| s == scene)
                .map(|(_, v, n)| (how, *v, n))
        });
        match other {
            Some((how, other, other_numbers))
                if matches!(
                    (verdict, other),
                    (Verdict::Confirmed, Verdict::NotConfirmed)
                        | (Verdict::NotConfirmed, Verdict::Confirmed)
                ) =>
            {
                (
                    Verdict::Fragile,
                    format!(
                        "{numbers} ({}); at {how}: {other_numbers} ({})",
                        verdict.word(),
                        other.word()
                    ),
                )
            }
            _ => (verdict, numbers.to_owned()),
        }
    }

    /// The coverage table: one row per claim of `inventory`, its verdicts over the scenes, or
    /// why it is not measured here; then the revisions.
    pub fn coverage(&self, inventory: &Inventory, history: Option<&History>) -> String {
        let mut md = String::from(
            "\n## Coverage: every claim of the inventory\n\n\
             One row per claim of the four papers' inventory (W = Wyman 2005a, N = Wyman 2005b, \
             U = Umenhoffer et al. 2007, K = Kakimoto et al. 2007) and per claim beyond the papers \
             (B). The tests and thresholds are data, stated before measuring \
             (`crates/refract-lab/claims.toml`); a test changed after it was measured is listed \
             under Revisions. *Stated* is read from git: the commit that gave the test its \
             present wording (`git blame` of its lines in `claims.toml`) against the first \
             commit of `docs/claims.md` with a row of that wording; a test counts as stated \
             before measuring only where the first is a strict ancestor of the second.\n\n\
             | id | claim (section) | verdict | where | stated |\n|---|---|---|---|---|\n",
        );
        // Counted apart: the papers' inventory (index 0) and the project's own claims (1).
        let (mut measured, mut confirmed, mut total) = ([0; 2], [0; 2], [0; 2]);
        let paper_ids = inventory_ids();
        for c in &inventory.claims {
            let own = usize::from(!paper_ids.contains(&c.id));
            total[own] += 1;
            let verdict = match (&c.not_measured, self.verdicts.get(&c.id)) {
                (Some(reason), _) => format!("not measured here: {reason}"),
                (None, None) => {
                    "**no row**: the test is stated but did not run (missing data?)".to_owned()
                }
                (None, Some(rows)) => {
                    measured[own] += 1;
                    let summary = summarise(rows);
                    if rows.iter().all(|(_, v)| *v == Verdict::Confirmed) {
                        confirmed[own] += 1;
                    }
                    summary
                }
            };
            let stated = match (&c.test, history) {
                (None, _) => "–".to_owned(),
                (Some(_), None) => "not known: no git history of the checkout".to_owned(),
                (Some(_), Some(h)) => h
                    .orders
                    .get(&c.id)
                    .map_or_else(|| "not known".to_owned(), Order::markdown),
            };
            let _ = writeln!(
                md,
                "| {} | {} ({}) | {verdict} | {} | {stated} |",
                c.id,
                c.words,
                c.section,
                self.sections.get(&c.id).map_or("–", String::as_str)
            );
        }
        let _ = writeln!(
            md,
            "\nThe papers' claims: {} of {} measured here, {} confirmed on every scene. The \
             project's own claims (B): {} of {} measured, {} confirmed on every scene.",
            measured[0], total[0], confirmed[0], measured[1], total[1], confirmed[1]
        );
        if let Some(h) = history {
            let before = h
                .orders
                .values()
                .filter(|o| matches!(o, Order::Before { .. }))
                .count();
            let _ = writeln!(
                md,
                "\nStated before measuring, by git: {before} of the {} tested claims; the others \
                 were stated with their measurement.",
                h.orders.len()
            );
            for mismatch in &h.date_mismatches {
                let _ = writeln!(
                    md,
                    "\n- a date of claims.toml that git contradicts: {mismatch}"
                );
            }
        }
        if !inventory.revisions.is_empty() {
            md.push_str(
                "\n## Revisions\n\nTests changed after they were measured, with the reason.\n\n\
                 | date | id | before | after | reason | commit |\n|---|---|---|---|---|---|\n",
            );
            for (k, r) in inventory.revisions.iter().enumerate() {
                let commit = history
                    .and_then(|h| h.revisions.get(k).cloned().flatten())
                    .map_or_else(|| "–".to_owned(), |c| format!("`{}`", c.hash));
                let _ = writeln!(
                    md,
                    "| {} | {} | {} | {} | {} | {commit} |",
                    r.date, r.id, r.before, r.after, r.reason
                );
            }
        }
        md
    }
}

/// "confirmed (2 of 2 scenes)", "not confirmed on chart; confirmed on sphere-igea", ...
fn summarise(rows: &[(String, Verdict)]) -> String {
    let n = rows.len();
    let count = |v: Verdict| rows.iter().filter(|(_, r)| *r == v).count();
    if count(Verdict::Confirmed) == n {
        return format!("**confirmed** ({n} of {n})");
    }
    let mut parts = Vec::new();
    for v in [
        Verdict::NotConfirmed,
        Verdict::Fragile,
        Verdict::Inconclusive,
        Verdict::Confirmed,
    ] {
        let scenes: Vec<&str> = rows
            .iter()
            .filter(|(_, r)| *r == v)
            .map(|(s, _)| s.as_str())
            .collect();
        if !scenes.is_empty() {
            parts.push(format!("{} on {}", v.markdown(), scenes.join(", ")));
        }
    }
    parts.join("; ")
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The robustness pass: a row confirmed at one resolution and not at the other is fragile,
    /// with both measurements, and counts as not confirmed everywhere; rows that agree, rows the
    /// second pass has not (or has inconclusive) and timing rows stay as measured.
    #[test]
    fn rows_that_flip_between_resolutions_are_fragile() {
        let inventory = Inventory::builtin().expect("inventory");
        let rows = |verdicts: &[(&str, Verdict)]| {
            let mut claim = inventory.claim("W1").expect("W1");
            for (scene, v) in verdicts {
                claim.push(((*scene).to_owned(), *v, format!("numbers on {scene}")));
            }
            claim
        };
        let mut second = Ledger::default();
        second.rows(
            &mut String::new(),
            "s",
            &[rows(&[
                ("sphere", Verdict::NotConfirmed),
                ("cow", Verdict::Confirmed),
                ("torus", Verdict::Inconclusive),
            ])],
        );
        let mut ledger = Ledger::with_second("384²".to_owned(), second);
        let mut md = String::new();
        ledger.rows(
            &mut md,
            "s",
            &[rows(&[
                ("sphere", Verdict::Confirmed),
                ("cow", Verdict::Confirmed),
                ("torus", Verdict::NotConfirmed),
                ("horse", Verdict::Confirmed),
            ])],
        );
        let line = |scene: &str| {
            md.lines()
                .find(|l| l.contains(&format!("| {scene} |")))
                .expect("a row")
                .to_owned()
        };
        assert!(line("sphere").ends_with("| **fragile** |"), "{md}");
        assert!(
            line("sphere").contains(
                "numbers on sphere (confirmed); at 384²: numbers on sphere (not confirmed)"
            ),
            "{md}"
        );
        assert!(line("cow").ends_with("| **confirmed** |"), "{md}");
        assert!(line("torus").ends_with("| **not confirmed** |"), "{md}");
        assert!(line("horse").ends_with("| **confirmed** |"), "{md}");
        let coverage = ledger.coverage(&inventory, None);
        let w1 = coverage
            .lines()
            .find(|l| l.starts_with("| W1 |"))
            .expect("W1's coverage row");
        assert!(w1.contains("**fragile** on sphere"), "{w1}");
    }

    /// The compiled-in file holds every inventory claim once and passes its own checks.
    #[test]
    fn the_claims_file_covers_the_inventory() {
        let inventory = Inventory::builtin().expect("claims.toml");
        assert_eq!(inventory_ids().len(), 64);
        for id in inventory_ids() {
            assert!(inventory.claims.iter().any(|c| c.id == id), "{id}");
        }
        let claim = inventory.claim("N1").expect("N1");
        assert!(claim.text.contains("less than 0.5 ×"), "{}", claim.text);
        assert_eq!(claim.threshold("ratio").expect("ratio"), 0.5);
        assert!(claim.threshold("nonsense").is_err());
        assert!(inventory.claim("W5").is_err(), "W5 is not measured");
    }

    /// A file missing a claim, a test naming an absent threshold, or a claim with both a test
    /// and a reason is refused.
    #[test]
    fn a_broken_claims_file_is_refused() {
        let without_k21 = CLAIMS_TOML.replace("id = \"K21\"", "id = \"K99\"");
        assert!(Inventory::parse(&without_k21).is_err());
        let bad_threshold = CLAIMS_TOML.replace("less than {ratio} ×", "less than {rate} ×");
        assert!(Inventory::parse(&bad_threshold).is_err());
        let both = CLAIMS_TOML.replace(
            "not_measured = \"a judgement of use\"",
            "not_measured = \"a judgement of use\"\ntest = \"x\"\nstated = \"2026-12-02\"",
        );
        assert!(Inventory::parse(&both).is_err());
    }

    /// Repeats on both sides of a threshold are inconclusive, never the last run's verdict.
    #[test]
    fn repeats_that_straddle_are_inconclusive() {
        assert_eq!(Verdict::of_repeats([true; 5]), Verdict::Confirmed);
        assert_eq!(Verdict::of_repeats([false; 5]), Verdict::NotConfirmed);
        assert_eq!(
            Verdict::of_repeats([true, true, false, true, true]),
            Verdict::Inconclusive
        );
    }

    /// The coverage has a row per claim: a stated test without rows says so, a reason is shown.
    #[test]
    fn coverage_lists_every_claim() {
        let inventory = Inventory::builtin().expect("claims.toml");
        let mut ledger = Ledger::default();
        let mut w1 = inventory.claim("W1").expect("W1");
        w1.push(("sphere".into(), true, "T2 1° vs 2°".into()));
        w1.push(("cow".into(), false, "T2 3° vs 2°".into()));
        let mut md = String::new();
        ledger.rows(&mut md, "Wyman 2005a", &[w1]);
        let coverage = ledger.coverage(&inventory, None);
        assert!(coverage.contains("| W1 |") && coverage.contains("**not confirmed** on cow"));
        assert!(coverage.contains("| W3 |") && coverage.contains("**no row**"));
        assert!(coverage.contains("not measured here: the Buddha mesh"));
        assert_eq!(
            coverage.lines().filter(|l| l.starts_with("| W")).count(),
            13
        );
    }
}
