//! The CLI's side of [`refract_lab::Progress`]: a bar per stage on stderr (indicatif), notes and
//! table rows printed above the bars.

use std::cell::RefCell;
use std::collections::BTreeMap;

use indicatif::{MultiProgress, ProgressBar, ProgressStyle};
use refract_lab::{Note, Progress};

/// Progress bars and notes on the terminal.
#[derive(Default)]
pub struct Bars {
    bars: MultiProgress,
    stages: RefCell<BTreeMap<String, ProgressBar>>,
}

impl Bars {
    /// No bars yet.
    pub fn new() -> Self {
        Self::default()
    }

    fn with_stage(&self, stage: &str, f: impl FnOnce(&ProgressBar)) {
        if let Some(bar) = self.stages.borrow().get(stage) {
            f(bar);
        }
    }
}

impl Progress for Bars {
    fn start(&self, stage: &str, total: u64) {
        let bar = self.bars.add(ProgressBar::new(total));
        if let Ok(style) =
            ProgressStyle::with_template("{msg:>12} [{bar:30}] {pos}/{len} {elapsed} (ETA {eta})")
        {
            bar.set_style(style.progress_chars("=> "));
        }
        bar.set_message(stage.to_owned());
        self.stages.borrow_mut().insert(stage.to_owned(), bar);
    }

    fn advance(&self, stage: &str, steps: u64) {
        self.with_stage(stage, |bar| bar.inc(steps));
    }

    fn finish(&self, stage: &str) {
        if let Some(bar) = self.stages.borrow_mut().remove(stage) {
            bar.finish_and_clear();
            self.bars.remove(&bar);
        }
    }

    fn note(&self, note: Note) {
        let line = note.to_string();
        // Rows of a table go to stdout, the rest to stderr; either above the bars.
        let print = || match note {
            Note::Row(_) => println!("{line}"),
            _ => eprintln!("{line}"),
        };
        if self.stages.borrow().is_empty() {
            print();
        } else {
            self.bars.suspend(print);
        }
    }
}
