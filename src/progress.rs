//! Progress on stderr for the command line: a bar (or spinner) when stderr
//! is a terminal, else one line per step — for `front` and `study` ([`Bar`]),
//! `design`'s outer iterations and stages ([`DesignProgress`]) and `size`'s
//! sections, outer iterations and stages ([`SizeProgress`]).

use indicatif::{ProgressBar, ProgressStyle};
use ringmesh::design::{DesignObserver, DesignStage, IterationRecord, RelaxationKind};
use ringmesh::run::{self, Progress};
use ringmesh::sizing::{SectionTrial, SizingObserver, TubeSection};

/// A progress bar on stderr (hidden when stderr is not a terminal).
pub struct Bar(pub ProgressBar);

impl Progress for Bar {
    fn start(&self, total: usize) {
        self.0.set_length(total as u64);
    }
    fn step(&self, message: &str) {
        self.0.set_message(message.to_string());
        self.0.inc(1);
        // Not on a terminal (a batch job's log): one line per step instead.
        if self.0.is_hidden() {
            eprintln!(
                "{}/{} {:.1} s {message}",
                self.0.position(),
                self.0.length().unwrap_or(0),
                self.0.elapsed().as_secs_f64()
            );
        }
    }
}

/// A progress bar on stderr; when stderr is not a terminal, one line per
/// finished step instead.
pub fn bar() -> Bar {
    let bar = ProgressBar::new(0);
    bar.set_style(
        ProgressStyle::with_template("{bar:40} {pos}/{len} {elapsed} {msg}")
            .expect("valid template"),
    );
    Bar(bar)
}

/// The progress of `design`: one line per outer iteration on stderr, then,
/// for the stages after the loop, a bar on a terminal, else one line as each
/// begins.
pub struct DesignProgress {
    pub bar: ProgressBar,
}

impl DesignProgress {
    pub fn new() -> Self {
        let bar = ProgressBar::new(DesignStage::ALL.len() as u64);
        bar.set_style(
            ProgressStyle::with_template("{bar:20} {pos}/{len} stages {elapsed} {msg}")
                .expect("valid template"),
        );
        DesignProgress { bar }
    }
}

impl DesignObserver for DesignProgress {
    fn iteration(&mut self, relaxation: RelaxationKind, record: &IterationRecord) {
        self.bar
            .suspend(|| eprintln!("{}", run::iteration_line(relaxation, record)));
    }
    fn stage(&mut self, stage: DesignStage) {
        let k = DesignStage::ALL
            .iter()
            .position(|s| *s == stage)
            .unwrap_or(0);
        if self.bar.is_hidden() {
            eprintln!(
                "stage {}/{} at {:.1} s: {}",
                k + 1,
                DesignStage::ALL.len(),
                self.bar.elapsed().as_secs_f64(),
                stage.description()
            );
        } else {
            self.bar.set_position(k as u64);
            self.bar.set_message(stage.description());
        }
    }
}

/// The progress of `size`: one line per section tried; within each
/// section's design a spinner on a terminal, else one line per outer
/// iteration and per stage after the loop.
pub struct SizeProgress {
    pub bar: ProgressBar,
}

impl SizeProgress {
    pub fn new() -> Self {
        let bar = ProgressBar::new_spinner();
        bar.set_style(
            ProgressStyle::with_template("{spinner} {elapsed} {msg}").expect("valid template"),
        );
        if !bar.is_hidden() {
            bar.enable_steady_tick(std::time::Duration::from_millis(200));
        }
        SizeProgress { bar }
    }

    /// A line of a section's design: on stderr off a terminal, else the
    /// spinner's message.
    fn say(&self, section: &TubeSection, what: String) {
        let line = format!(
            "{:.1}/{:.1} mm tube: {what}",
            1e3 * section.outer_diameter_m,
            1e3 * section.inner_diameter_m
        );
        if self.bar.is_hidden() {
            eprintln!("  {line}");
        } else {
            self.bar.set_message(line);
        }
    }
}

impl SizingObserver for SizeProgress {
    fn trial(&mut self, trial: &SectionTrial) {
        self.bar
            .suspend(|| eprintln!("{}", run::section_line(trial)));
    }
    fn iteration(
        &mut self,
        section: &TubeSection,
        relaxation: RelaxationKind,
        r: &IterationRecord,
    ) {
        self.say(
            section,
            run::iteration_line(relaxation, r).trim_start().to_string(),
        );
    }
    fn stage(&mut self, section: &TubeSection, stage: DesignStage) {
        self.say(section, stage.description().to_string());
    }
}
