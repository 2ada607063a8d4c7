//! When each claim's test was stated and when it was first measured, read from git (issue 51):
//! the commit that gave the test its current wording (`git blame` of its `test` and
//! `thresholds` lines in `crates/refract-lab/claims.toml`) against the first commit of
//! `docs/claims.md` with a row of that wording (`git log -S`). A test is *stated before
//! measuring* only where the first is a strict ancestor of the second, or where no row of it was
//! ever committed (this run measures it first); otherwise it was stated with its measurement.
//! Nothing here is typed: where git or the history is missing, the column says so.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;

use super::inventory::{ClaimSpec, Inventory};

/// The claims file and the document, relative to the repository's root.
const CLAIMS_TOML: &str = "crates/refract-lab/claims.toml";
const CLAIMS_MD: &str = "docs/claims.md";

/// A commit: its short hash and its committer date (UTC, `YYYY-MM-DD`).
#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) struct Commit {
    pub hash: String,
    pub date: String,
}

impl Commit {
    fn markdown(&self) -> String {
        format!("`{}` ({})", self.hash, self.date)
    }
}

/// The order of a test's statement and its first measurement.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) enum Order {
    /// Stated in `stated`, a strict ancestor of `measured`, the first commit with a row of it;
    /// `measured` is `None` where no row of it was committed yet: this run measures it first.
    Before {
        stated: Commit,
        measured: Option<Commit>,
    },
    /// The first row of this wording is in the commit that stated it, or in one before it.
    With { stated: Commit, measured: Commit },
    /// The wording is not committed (the checkout or the build differs from HEAD).
    Uncommitted,
}

impl Order {
    /// The coverage table's cell.
    pub fn markdown(&self) -> String {
        match self {
            Self::Before {
                stated,
                measured: Some(m),
            } => format!(
                "stated in {}, before its first measured row in {}",
                stated.markdown(),
                m.markdown()
            ),
            Self::Before {
                stated,
                measured: None,
            } => format!(
                "stated in {}; first measured by this run",
                stated.markdown()
            ),
            Self::With { stated, measured } if stated == measured => {
                format!("stated with its measurement, in {}", stated.markdown())
            }
            Self::With { stated, measured } => format!(
                "stated with its measurement: first measured row in {}, wording committed in {}",
                measured.markdown(),
                stated.markdown()
            ),
            Self::Uncommitted => {
                "stated with its measurement (the wording is not committed)".into()
            }
        }
    }
}

/// Per claim id, the order of its statement and measurement; per revision (in the file's
/// order), the commit that recorded it.
#[derive(Debug, Default)]
pub(crate) struct History {
    pub orders: BTreeMap<String, Order>,
    pub revisions: Vec<Option<Commit>>,
    /// The `stated` dates and revision dates that differ from their commits' dates.
    pub date_mismatches: Vec<String>,
}

/// Runs git in `root` and returns its standard output, `None` if it fails.
fn git(root: &Path, args: &[&str]) -> Option<String> {
    let out = Command::new("git")
        .arg("-C")
        .arg(root)
        .args(args)
        .env("TZ", "UTC")
        .output()
        .ok()
        .filter(|out| out.status.success())?;
    Some(String::from_utf8_lossy(&out.stdout).into_owned())
}

/// The root of the git checkout that holds `dir`, if it holds the claims file and its history
/// is complete (not a shallow clone).
pub(crate) fn repository(dir: &Path) -> Option<PathBuf> {
    let root = PathBuf::from(git(dir, &["rev-parse", "--show-toplevel"])?.trim());
    let shallow = git(&root, &["rev-parse", "--is-shallow-repository"])?;
    (shallow.trim() == "false" && root.join(CLAIMS_TOML).is_file()).then_some(root)
}

/// Per line of `path` at HEAD (0-based), the commit that last changed it: `git blame
/// --porcelain`, each commit with its committer date.
fn blame(root: &Path, path: &str) -> Option<Vec<Commit>> {
    let text = git(root, &["blame", "--porcelain", "HEAD", "--", path])?;
    let mut dates: BTreeMap<String, String> = BTreeMap::new();
    let mut lines = Vec::new();
    let mut current: Option<String> = None;
    for line in text.lines() {
        if line.starts_with('\t') {
            let hash = current.take()?;
            let date = dates.get(&hash)?.clone();
            lines.push(Commit {
                hash: hash[..7].to_owned(),
                date,
            });
        } else if let Some(time) = line.strip_prefix("committer-time ") {
            let seconds: i64 = time.trim().parse().ok()?;
            dates.insert(current.clone()?, utc_date(seconds));
        } else if current.is_none() {
            let hash = line.split(' ').next()?;
            if hash.len() == 40 && hash.bytes().all(|b| b.is_ascii_hexdigit()) {
                current = Some(hash.to_owned());
            }
        }
    }
    Some(lines)
}

/// `YYYY-MM-DD` of a Unix time in UTC (the civil-from-days algorithm of Howard Hinnant).
fn utc_date(seconds: i64) -> String {
    let days = seconds.div_euclid(86_400);
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let day = doy - (153 * mp + 2) / 5 + 1;
    let month = if mp < 10 { mp + 3 } else { mp - 9 };
    let year = yoe + era * 400 + i64::from(month <= 2);
    format!("{year:04}-{month:02}-{day:02}")
}

/// The 0-based line numbers of each claim's `test` and `thresholds` lines and of each
/// revision's `date` line, by their position in a claims file's text.
#[derive(Debug, Default, PartialEq)]
struct Lines {
    claims: BTreeMap<String, Vec<usize>>,
    revision_dates: Vec<usize>,
}

fn lines_of(text: &str) -> Lines {
    let mut lines = Lines::default();
    // The block being read: a claim (its id once read) or a revision.
    let mut claim: Option<Option<String>> = None;
    let mut pending = Vec::new();
    for (k, line) in text.lines().enumerate() {
        let line = line.trim_start();
        let new_block = line.starts_with("[[claim]]") || line.starts_with("[[revision]]");
        if new_block {
            if let Some(Some(id)) = claim.take() {
                lines.claims.insert(id, std::mem::take(&mut pending));
            }
            pending.clear();
            claim = line.starts_with("[[claim]]").then_some(None);
        } else if let Some(id) = &mut claim {
            if let Some(v) = line.strip_prefix("id = ") {
                *id = Some(v.trim().trim_matches('"').to_owned());
            } else if line.starts_with("test = ") || line.starts_with("thresholds = ") {
                pending.push(k);
            }
        } else if line.starts_with("date = ") {
            lines.revision_dates.push(k);
        }
    }
    if let Some(Some(id)) = claim {
        lines.claims.insert(id, pending);
    }
    lines
}

impl History {
    /// The history of `inventory` (the claims the binary was built with) in the checkout at
    /// `root` (see [`repository`]); `None` where git fails.
    pub fn read(root: &Path, inventory: &Inventory) -> Option<Self> {
        let head_text = git(root, &["show", &format!("HEAD:{CLAIMS_TOML}")])?;
        let head = Inventory::parse(&head_text).ok()?;
        let lines = lines_of(&head_text);
        let blamed = blame(root, CLAIMS_TOML)?;
        let mut history = Self::default();
        for spec in inventory.claims.iter().filter(|c| c.test.is_some()) {
            let committed = head.claims.iter().find(|c| c.id == spec.id);
            let same =
                committed.is_some_and(|c| c.test == spec.test && c.thresholds == spec.thresholds);
            let order = match (same, lines.claims.get(&spec.id)) {
                (true, Some(ks)) if !ks.is_empty() => {
                    let stated = latest(root, ks.iter().filter_map(|&k| blamed.get(k)))?;
                    let measured = first_row(root, spec)?;
                    order(root, stated, measured)
                }
                _ => Order::Uncommitted,
            };
            if let Some(date) = &spec.stated
                && let Order::Before { stated, .. } | Order::With { stated, .. } = &order
                && *date != stated.date
            {
                history.date_mismatches.push(format!(
                    "{}: stated = \"{date}\", its wording was committed on {} ({})",
                    spec.id, stated.date, stated.hash
                ));
            }
            history.orders.insert(spec.id.clone(), order);
        }
        for (r, &k) in head.revisions.iter().zip(&lines.revision_dates) {
            let commit = blamed.get(k).cloned();
            if let Some(c) = &commit
                && c.date != r.date
            {
                history.date_mismatches.push(format!(
                    "revision of {}: date = \"{}\", committed on {} ({})",
                    r.id, r.date, c.date, c.hash
                ));
            }
            history.revisions.push(commit);
        }
        Some(history)
    }
}

/// The latest of `commits` (each an ancestor of HEAD): the one the others are ancestors of.
fn latest<'a>(root: &Path, commits: impl Iterator<Item = &'a Commit>) -> Option<Commit> {
    let mut best: Option<&Commit> = None;
    for c in commits {
        best = match best {
            Some(b) if is_ancestor(root, &c.hash, &b.hash) => Some(b),
            _ => Some(c),
        };
    }
    best.cloned()
}

/// Whether `a` is an ancestor of `b` (or the same commit).
fn is_ancestor(root: &Path, a: &str, b: &str) -> bool {
    Command::new("git")
        .arg("-C")
        .arg(root)
        .args(["merge-base", "--is-ancestor", a, b])
        .status()
        .is_ok_and(|s| s.success())
}

/// The first commit of `docs/claims.md` whose text has a row of `spec`'s wording (its id, words,
/// section and test with the thresholds filled in, as the rows print it); `Some(None)` where
/// none has.
fn first_row(root: &Path, spec: &ClaimSpec) -> Option<Option<Commit>> {
    let row = super::inventory::row_text(spec)?;
    let out = git(
        root,
        &[
            "log",
            "--reverse",
            "--format=%h %cd",
            "--date=format-local:%Y-%m-%d",
            "--abbrev=7",
            &format!("-S{row}"),
            "HEAD",
            "--",
            CLAIMS_MD,
        ],
    )?;
    Some(out.lines().next().and_then(|line| {
        let (hash, date) = line.split_once(' ')?;
        Some(Commit {
            hash: hash.to_owned(),
            date: date.to_owned(),
        })
    }))
}

/// Stated in `stated`, first measured in `measured`: before only where `stated` is a strict
/// ancestor of `measured`.
fn order(root: &Path, stated: Commit, measured: Option<Commit>) -> Order {
    match measured {
        None => Order::Before {
            stated,
            measured: None,
        },
        Some(m) if m.hash != stated.hash && is_ancestor(root, &stated.hash, &m.hash) => {
            Order::Before {
                stated,
                measured: Some(m),
            }
        }
        Some(m) => Order::With {
            stated,
            measured: m,
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dates_are_utc_days() {
        assert_eq!(utc_date(0), "1970-01-01");
        assert_eq!(utc_date(1_796_240_069), "2026-12-02");
        assert_eq!(utc_date(951_782_400), "2000-02-29");
        assert_eq!(utc_date(-1), "1969-12-31");
    }

    #[test]
    fn lines_are_found_per_claim_and_revision() {
        let text = "# c\n[[claim]]\nid = \"W1\"\ntest = \"t {x}\"\nstated = \"2026-12-02\"\nthresholds = { x = 1.0 }\n\n[[claim]]\nid = \"W5\"\nnot_measured = \"no\"\n\n[[revision]]\ndate = \"2026-12-03\"\nid = \"W1\"\n";
        let lines = lines_of(text);
        assert_eq!(lines.claims["W1"], vec![3, 5]);
        assert!(lines.claims["W5"].is_empty());
        assert_eq!(lines.revision_dates, vec![12]);
    }

    /// The order says "before" only for a strict ancestor: a row in the stating commit is
    /// "with its measurement".
    #[test]
    fn a_row_in_the_stating_commit_is_not_before() {
        let c = |h: &str| Commit {
            hash: h.into(),
            date: "2026-12-07".into(),
        };
        let here = Path::new(".");
        assert_eq!(
            order(here, c("abc1234"), Some(c("abc1234"))),
            Order::With {
                stated: c("abc1234"),
                measured: c("abc1234")
            }
        );
        assert!(matches!(
            order(here, c("abc1234"), None),
            Order::Before { measured: None, .. }
        ));
        assert!(
            Order::Uncommitted
                .markdown()
                .contains("with its measurement")
        );
    }

    /// In this repository (where its history is present), every `stated` date and revision
    /// date is the date of the commit that wrote it, and the claims stated in 85945dd were
    /// stated before their measurement.
    #[test]
    fn stated_dates_are_true_to_git() {
        // The test's own skip line (the library itself never prints: dependency_rule.rs).
        let skip = |why: &str| {
            use std::io::Write as _;
            let _ = writeln!(std::io::stdout(), "skipped: {why}");
        };
        let Some(root) = repository(Path::new(env!("CARGO_MANIFEST_DIR"))) else {
            skip("no git history of the repository");
            return;
        };
        let inventory = Inventory::builtin().expect("claims.toml");
        let Some(history) = History::read(&root, &inventory) else {
            skip("git could not read the history");
            return;
        };
        assert!(
            history.date_mismatches.is_empty(),
            "{:#?}",
            history.date_mismatches
        );
        // Both orders occur: the claims stated with the claims file itself (ed108ca, with
        // their first rows) and the ones stated in a commit of their own.
        let (before, with) = history.orders.values().fold((0, 0), |(b, w), o| match o {
            Order::Before { .. } => (b + 1, w),
            Order::With { .. } => (b, w + 1),
            Order::Uncommitted => (b, w),
        });
        assert!(before > 0 && with > 0, "{:#?}", history.orders);
        assert_eq!(history.revisions.len(), inventory.revisions.len());
    }
}
