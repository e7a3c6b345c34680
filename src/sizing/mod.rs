//! Sizing the ring truss for its net (issue 16): the lightest tube section
//! whose design has a limit margin of at least `M` (DESIGN §9).
//!
//! The pull a net puts on its truss depends on how the truss deforms, so a
//! section is judged by the whole `design` job on the scene made of it
//! ([`crate::design::run`]: the outer loop, the margin of the truss to its
//! limit load under the converged design's pull, the assembly): it *carries*
//! the net when the loop converges and the margin — the certified stable
//! multiple of the pull, [`LimitSearch::stable_to`] — is at least `M`.
//!
//! Every rod of the truss gets the one section: the scene has one tube, and
//! the limit mode of the shipped rings (the oval distortion of both rings,
//! [`crate::truss::limit_margin`]) engages battens, longerons and diagonals
//! together, so no family can be thinned without lowering the margin the
//! others carry. Two searches:
//!
//! * **catalogue**: the sections ([`catalogue`]) lightest first, those
//!   heavier and no stiffer than a lighter one left out; the lightest that
//!   carries found by bisection, the margin growing with the section
//!   (the one before it was tried and does not carry);
//! * **continuous**: the outer diameter at the scene's `d/D` (wall
//!   thickness ratio) and material, in steps of 0.1 mm, from a model of the
//!   margin `m ∝ D^p` (`p = 4`, the bending stiffness's exponent, until two
//!   designs measure it) bracketed and narrowed until the lightest carrying
//!   diameter is within 0.5 % of one that does not, or its margin is within
//!   3 % of `M`.
//!
//! The sized scene is written as the input's own text with the tube lines
//! changed ([`sized_scene_text`]).

pub mod catalogue;
mod error;
mod scene_file;

use std::time::Instant;

use clap::ValueEnum;
use serde::Serialize;

pub use catalogue::TubeSection;
pub use error::SizingError;
pub use scene_file::sized_scene_text;

use crate::design::{
    DesignError, DesignObserver, DesignRun, DesignSettings, DesignStage, IterationRecord,
    LoopSummary, RelaxationKind,
};
use crate::geometry::RingTrussLayout;
use crate::mechanics::LimitBound;
#[cfg(doc)]
use crate::mechanics::LimitSearch;
use crate::scene::{Scene, TrussModel};
use crate::status::Termination;
use crate::truss::{self, TrussError, MARGIN_SEARCH_TO as SEARCH_TO};

/// Where the sections come from.
#[derive(Debug, Clone)]
pub enum Sections {
    /// A catalogue's sections ([`catalogue::read`]).
    Catalogue(Vec<TubeSection>),
    /// Any outer diameter at the scene's `d/D` and material, the search
    /// starting at this outer diameter, m.
    Continuous {
        /// The first outer diameter tried, m.
        start_m: f64,
    },
}

/// One section tried: its design's figures.
#[derive(Debug, Clone, Serialize)]
pub struct SectionTrial {
    /// The section.
    pub section: TubeSection,
    /// Mass of the truss's tubes, kg.
    pub mass_kg: f64,
    /// The certified stable multiple of the design's pull (0 when the truss
    /// finds no stable equilibrium under it).
    pub margin: f64,
    /// What bounds the limit load from above, when the margin was searched.
    pub bound: Option<LimitBound>,
    /// How the design's outer loop ended, its iterations, final residual
    /// and wall time, when it ran to the end. Not flattened: its `time_s`
    /// (the loop's) would collide with the trial's (the whole design's).
    pub summary: Option<LoopSummary>,
    /// Surface RMS of the design as built (assembled), mm.
    pub rms_mm: Option<f64>,
    /// Wall time of the design, s.
    pub time_s: f64,
    /// True when the loop converged and the margin is at least the one asked.
    pub carries: bool,
    /// Why there is no design, when there is none.
    pub failure: Option<String>,
}

/// A sizing's outcome.
#[derive(Debug)]
pub struct Sizing {
    /// The margin asked for.
    pub margin: f64,
    /// Every section tried, in the order tried.
    pub trials: Vec<SectionTrial>,
    /// The lightest section that carries: an index into `trials`.
    pub chosen: usize,
    /// The scene with its truss made of the chosen section.
    pub scene: Scene,
    /// The chosen section's design run.
    pub run: DesignRun,
}

/// Designs one steps of the continuous search: 0.1 mm.
const DIAMETER_STEP_M: f64 = 1e-4;

/// The continuous search stops when the lightest carrying diameter is within
/// this fraction of one that does not carry…
const DIAMETER_PRECISION: f64 = 0.005;

/// …or its margin within this fraction above the one asked for.
const MARGIN_SLACK: f64 = 0.03;

/// Designs a continuous search may make.
const MAX_DESIGNS: usize = 16;

/// The lightest section of `sections` on which `scene`'s design (with
/// `settings`, on a truss model with a limit load,
/// [`truss::has_limit_load`]) has a limit margin of at least `margin`;
/// `observe` sees each section tried.
///
/// # Errors
/// A margin outside `[1, SEARCH_TO]`, a scene whose truss is measured rod
/// by rod (`effects.rod_properties_csv`) or on a model without a limit
/// load, an invalid section,
/// a design that fails for another reason than its truss (no tube would
/// help), or no section that carries ([`SizingError::NoSection`]).
pub fn size_truss(
    scene: &Scene,
    sections: &Sections,
    margin: f64,
    settings: &DesignSettings,
    observe: &mut dyn FnMut(&SectionTrial),
) -> Result<Sizing, SizingError> {
    size_truss_observed(scene, sections, margin, settings, &mut Trials(observe))
}

/// Sees a sizing as it goes; every method does nothing by default.
pub trait SizingObserver {
    /// A section was tried (its design finished, or failed).
    fn trial(&mut self, _trial: &SectionTrial) {}
    /// An outer iteration of the design on `section` finished.
    fn iteration(
        &mut self,
        _section: &TubeSection,
        _relaxation: RelaxationKind,
        _record: &IterationRecord,
    ) {
    }
    /// A stage after the design loop on `section` begins.
    fn stage(&mut self, _section: &TubeSection, _stage: DesignStage) {}
}

/// An observer of the sections tried alone.
struct Trials<'a>(&'a mut dyn FnMut(&SectionTrial));

impl SizingObserver for Trials<'_> {
    fn trial(&mut self, trial: &SectionTrial) {
        (self.0)(trial)
    }
}

/// A sizing's observer seen by one section's design.
struct SectionDesign<'a> {
    section: &'a TubeSection,
    observer: &'a mut dyn SizingObserver,
}

impl DesignObserver for SectionDesign<'_> {
    fn iteration(&mut self, relaxation: RelaxationKind, record: &IterationRecord) {
        self.observer.iteration(self.section, relaxation, record)
    }
    fn stage(&mut self, stage: DesignStage) {
        self.observer.stage(self.section, stage)
    }
}

/// [`size_truss`], with `observer` told of each section tried and of each
/// outer iteration and stage of its design.
///
/// # Errors
/// As [`size_truss`].
pub fn size_truss_observed(
    scene: &Scene,
    sections: &Sections,
    margin: f64,
    settings: &DesignSettings,
    observe: &mut dyn SizingObserver,
) -> Result<Sizing, SizingError> {
    if !((1.0..=SEARCH_TO).contains(&margin)) {
        return Err(SizingError::Margin {
            value: margin,
            max: SEARCH_TO,
        });
    }
    if scene.effects.rod_properties_csv.is_some() {
        return Err(SizingError::Scene {
            key: "effects.rod_properties_csv",
            reason: "the rods are measured one by one; sizing sets the nominal tube of every rod"
                .into(),
        });
    }
    let model = settings.truss.unwrap_or(scene.effects.truss);
    if !truss::has_limit_load(model) {
        let name = |m: &TrussModel| {
            m.to_possible_value()
                .map_or_else(|| format!("{m:?}"), |v| v.get_name().to_owned())
        };
        let with: Vec<String> = truss::MODELS
            .iter()
            .filter(|m| truss::has_limit_load(**m))
            .map(name)
            .collect();
        return Err(SizingError::Scene {
            key: "effects.truss",
            reason: format!(
                "sizing needs a truss model with a limit load ({}); the {} truss has none",
                with.join(", "),
                name(&model)
            ),
        });
    }
    let mut search = Search {
        scene,
        margin,
        settings,
        observe,
        trials: Vec::new(),
        best: None,
    };
    match sections {
        Sections::Catalogue(list) => search.catalogue(&catalogue::undominated(list))?,
        Sections::Continuous { start_m } => search.continuous(*start_m)?,
    }
    let Some((chosen, run)) = search.best else {
        let stiffest = search
            .trials
            .iter()
            .max_by(|a, b| {
                a.section
                    .bending_stiffness_nm2()
                    .total_cmp(&b.section.bending_stiffness_nm2())
            })
            .expect("a section was tried");
        return Err(SizingError::NoSection {
            margin,
            outer_mm: 1e3 * stiffest.section.outer_diameter_m,
            inner_mm: 1e3 * stiffest.section.inner_diameter_m,
            best: stiffest.margin,
            detail: stiffest.failure.clone(),
        });
    };
    let mut sized = scene.clone();
    sized.truss = search.trials[chosen].section.apply(&scene.truss);
    Ok(Sizing {
        margin,
        trials: search.trials,
        chosen,
        scene: sized,
        run,
    })
}

/// A sizing in progress.
struct Search<'a> {
    scene: &'a Scene,
    margin: f64,
    settings: &'a DesignSettings,
    observe: &'a mut dyn SizingObserver,
    trials: Vec<SectionTrial>,
    /// The lightest carrying trial so far and its run.
    best: Option<(usize, DesignRun)>,
}

impl Search<'_> {
    /// Designs on `section`: whether it carries.
    fn try_section(&mut self, section: TubeSection) -> Result<bool, SizingError> {
        let mut scene = self.scene.clone();
        scene.truss = section.apply(&self.scene.truss);
        scene.validate()?;
        let mass_kg =
            RingTrussLayout::of(&scene).rod_length_m() * section.mass_per_length_kg_per_m();
        let clock = Instant::now();
        let result = crate::design::run_observed(
            &scene,
            self.settings,
            &mut SectionDesign {
                section: &section,
                observer: &mut *self.observe,
            },
        );
        let time_s = clock.elapsed().as_secs_f64();
        let mut trial = SectionTrial {
            section,
            mass_kg,
            margin: 0.0,
            bound: None,
            summary: None,
            rms_mm: None,
            time_s,
            carries: false,
            failure: None,
        };
        let mut run = None;
        match result {
            Ok(r) => {
                let report = &r.report;
                let limit = report.limit_margin.as_ref();
                trial.margin = limit.map_or(0.0, |m| m.stable_to);
                trial.bound = limit.map(|m| m.bound);
                let summary = report.design_summary();
                trial.summary = Some(summary);
                trial.rms_mm = Some(report.verification.rms_mm);
                trial.carries =
                    summary.termination == Termination::Converged && trial.margin >= self.margin;
                run = Some(r);
            }
            Err(e) => match truss_failure(&e) {
                // The tube is too weak: this section does not carry.
                Some(TrussError::PastLimitLoad { stable_to, bound }) => {
                    trial.margin = *stable_to;
                    trial.bound = Some(*bound);
                    trial.failure = Some(e.to_string());
                }
                Some(TrussError::NoEquilibrium { .. }) => trial.failure = Some(e.to_string()),
                // Not the tube's doing: no section would design.
                _ => return Err(e.into()),
            },
        }
        self.observe.trial(&trial);
        let carries = trial.carries;
        self.trials.push(trial);
        if let Some(run) = run.filter(|_| carries) {
            let index = self.trials.len() - 1;
            let lighter = self
                .best
                .as_ref()
                .is_none_or(|(b, _)| self.trials[index].mass_kg < self.trials[*b].mass_kg);
            if lighter {
                self.best = Some((index, run));
            }
        }
        Ok(carries)
    }

    /// Bisection on `sections` (lightest first): the first that carries.
    fn catalogue(&mut self, sections: &[TubeSection]) -> Result<(), SizingError> {
        let (mut lo, mut hi) = (0, sections.len());
        while lo < hi {
            let mid = (lo + hi) / 2;
            if self.try_section(sections[mid])? {
                hi = mid;
            } else {
                lo = mid + 1;
            }
        }
        Ok(())
    }

    /// The outer diameter at the scene's `d/D`, from `start_m`.
    fn continuous(&mut self, start_m: f64) -> Result<(), SizingError> {
        let base = TubeSection::of(&self.scene.truss);
        let ratio = base.inner_diameter_m / base.outer_diameter_m;
        let section = |outer: f64| TubeSection {
            outer_diameter_m: outer,
            inner_diameter_m: ratio * outer,
            ..base
        };
        let quantise = |d: f64| (d / DIAMETER_STEP_M).round().max(1.0) * DIAMETER_STEP_M;
        let target = self.margin * (1.0 + 0.5 * MARGIN_SLACK);
        // The largest diameter that does not carry and the least that does,
        // with their margins.
        let mut below: Option<(f64, f64)> = None;
        let mut above: Option<(f64, f64)> = None;
        let mut diameter = quantise(start_m);
        for _ in 0..MAX_DESIGNS {
            if self
                .trials
                .iter()
                .any(|t| t.section.outer_diameter_m == diameter)
            {
                break;
            }
            let carries = self.try_section(section(diameter))?;
            let m = self.trials.last().expect("just tried").margin;
            if carries {
                above = Some((diameter, m));
            } else {
                below = Some((diameter, m));
            }
            if let Some((d_hi, m_hi)) = above {
                let narrow = below.is_some_and(|(d_lo, _)| {
                    d_hi - d_lo <= (DIAMETER_PRECISION * d_hi).max(DIAMETER_STEP_M)
                });
                if narrow || m_hi <= self.margin * (1.0 + MARGIN_SLACK) {
                    break;
                }
            }
            let next = match (below, above) {
                (Some((d_lo, m_lo)), Some((d_hi, m_hi))) => {
                    // The margin's exponent between the bracket's ends.
                    let p = if m_lo > 0.0 {
                        ((m_hi / m_lo).ln() / (d_hi / d_lo).ln()).clamp(1.0, 8.0)
                    } else {
                        4.0
                    };
                    let guess = if m_lo > 0.0 {
                        d_lo * (target / m_lo).powf(1.0 / p)
                    } else {
                        d_hi * (target / m_hi).powf(1.0 / p)
                    };
                    let gap = d_hi - d_lo;
                    guess.clamp(d_lo + 0.1 * gap, d_hi - 0.1 * gap)
                }
                (Some((d, m)), None) if m > 0.0 => {
                    (d * (target / m).powf(0.25)).clamp(1.05 * d, 4.0 * d)
                }
                (Some((d, _)), None) => 2.0 * d,
                (None, Some((d, m))) => (d * (target / m).powf(0.25)).clamp(0.25 * d, 0.95 * d),
                (None, None) => unreachable!("a diameter was tried"),
            };
            diameter = quantise(next);
        }
        Ok(())
    }
}

/// The truss's failure inside `e`, if it is one.
fn truss_failure(e: &DesignError) -> Option<&TrussError> {
    match e {
        DesignError::RingTruss(t) | DesignError::Truss { source: t, .. } => Some(t),
        _ => None,
    }
}
