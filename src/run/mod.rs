//! One file per CLI subcommand: read the inputs, call the library, write the
//! outputs (all together or none, into a folder locked and checked before
//! any computing: [`OutputSet`]), and return what the command made, whose
//! `summary()` is what the command prints ([`Summary`]: its lines and how the
//! run ended). `main.rs` only parses arguments, calls these, prints the
//! summary and maps it to an exit code; the pipelines themselves live in the
//! library ([`crate::design::run`], [`crate::study::run_study`], …).

/// Appends one formatted entry to a [`Summary`]'s lines.
macro_rules! say {
    ($summary:expr, $($arg:tt)*) => {
        $summary.lines.push(format!($($arg)*))
    };
}

mod apertures;
mod budget;
mod cantilever;
mod design;
mod fdm;
mod frame;
mod front;
mod init;
mod merge;
mod mesh;
mod optimize;
mod size;
mod study;
mod truss;
mod uniformity;

use std::path::{Path, PathBuf};

pub use apertures::{aperture_line, apertures, AperturesOutcome};
pub use budget::{budget, BudgetOutcome};
pub use cantilever::{cantilever, CantileverTable, CantileverTableRow};
pub use design::{design, design_observed, iteration_line, DesignOutcome};
pub use fdm::{fdm, FdmOutcome, FdmOutput};
pub use frame::{
    default_frame_output, frame, FrameCounts, FrameNodeOutput, FrameOutcome, FrameOutput,
    FrameReaction,
};
pub use front::{front, front_points, FrontOutcome};
pub use init::{default_init_path, init, InitOutcome};
pub use merge::{merge, MergeOutcome, MergedTable};
pub use mesh::{mesh, MeshOutcome};
pub use optimize::{optimize, OptimizeOutcome};
pub use size::{section_line, size, SizeOutcome};
pub use study::{study, study_rows, StudyOptions, StudyOutcome, STRATEGIES_STEM, STUDY_STEM};
pub use truss::{truss, TrussOutcome};
pub use uniformity::{
    uniformity, uniformity_of, uniformity_problem, UniformityOutcome, UniformityOutput,
};

use crate::report::{readable, OutputSet};
use crate::scene::Scene;
use crate::shard::{self, Shard, ShardHeader};
use crate::Error;

/// Progress of a long command; the CLI attaches a progress bar, the library
/// never prints.
pub trait Progress: Sync {
    /// The command will report `total` steps.
    fn start(&self, _total: usize) {}
    /// One step finished.
    fn step(&self, _message: &str) {}
}

/// What a command prints on stdout, and how its run ended.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Summary {
    /// The text, in order: each entry is printed followed by a newline (an
    /// entry may itself hold several lines).
    pub lines: Vec<String>,
    /// Why a run that wrote its results ended before its target (a `frame`
    /// run short of the full load, a design loop stopped before its
    /// tolerance), as the sentence the CLI prints on stderr before it exits
    /// 3; `None` when it reached it.
    pub ended_early: Option<String>,
}

impl Summary {
    /// One `wrote PATH` line per file written.
    pub(crate) fn written(&mut self, paths: &[PathBuf]) {
        for path in paths {
            say!(self, "wrote {}", path.display());
        }
    }
}

/// A [`Progress`] that ignores everything.
pub struct Silent;

impl Progress for Silent {}

/// Reads a scene file and completes it: a front net the file leaves to
/// `[surface] rms_mm` becomes the coarsest net that meets it
/// ([`crate::surface::resolve_front_rings`]).
///
/// # Errors
/// The scene's errors; a target no net meets.
pub fn read_scene(path: &Path) -> Result<Scene, crate::Error> {
    Ok(crate::surface::resolve_front_rings(&Scene::read(path)?)?)
}

/// What a summary says of the scene's surface target, if it has one: how
/// the rings were chosen for it, or whether the rings the file gives meet it
/// (`facet_rms_mm`: the design surface's facet RMS with those rings).
pub(crate) fn target_line(scene: &Scene, facet_rms_mm: f64) -> Option<String> {
    let target = scene.surface.rms_mm?;
    let rings = scene.front_net.rings;
    Some(match &scene.front_net.chosen {
        Some(c) => format!(
            "front net: {rings} rings, the coarsest whose facet RMS (design surface) meets \
             [surface] rms_mm = {} mm: {} mm{} ({} nets measured)",
            readable(target, 4),
            readable(c.facet_rms_mm, 4),
            c.next_coarser.map_or(String::new(), |(r, f)| format!(
                "; {r} rings give {} mm",
                readable(f, 4)
            )),
            c.nets_built
        ),
        None if facet_rms_mm <= target => format!(
            "[surface] rms_mm = {} mm: met by the front net's {rings} rings (facet RMS, \
             design surface, {} mm)",
            readable(target, 4),
            readable(facet_rms_mm, 4)
        ),
        None => format!(
            "[surface] rms_mm = {} mm: NOT met by the front net's {rings} rings (facet RMS, \
             design surface, {} mm); give more rings, or leave front_net.rings out to have \
             the coarsest net that meets it chosen",
            readable(target, 4),
            readable(facet_rms_mm, 4)
        ),
    })
}

/// The folder every command writes under when `-o` is not given: `runs/`,
/// which git ignores, so that no command writes over the committed results in
/// `results/` unless `-o` names them.
pub const RUNS_DIR: &str = "runs";

/// Where a scene's results go by default: `runs/<scene name>/`.
pub fn default_output_dir(scene: &Scene) -> PathBuf {
    default_dir_named(&scene.name)
}

/// `runs/<name>/`: the default folder of a run named `name` (a scene's name,
/// a frame file's stem).
pub fn default_dir_named(name: &str) -> PathBuf {
    Path::new(RUNS_DIR).join(name)
}

/// Writes a shard's CSV, `<stem>.shard-I-of-N.csv`, in `dir`; the sweep's
/// `points` dealt in `units` ([`Shard::points_in_units`]).
#[allow(clippy::too_many_arguments)]
pub(crate) fn write_shard(
    dir: &Path,
    stem: &str,
    command: &str,
    scene: &Scene,
    shard: Shard,
    (points, units): (usize, Vec<usize>),
    settings: serde_json::Value,
    columns: &str,
    rows: &[(usize, String)],
) -> Result<PathBuf, Error> {
    let header = ShardHeader {
        command: command.to_string(),
        scene: scene.name.clone(),
        shard,
        points,
        settings,
        scene_file: serde_json::to_value(scene).expect("a scene serialises"),
        units,
    };
    let csv = shard::shard_csv(&header, columns, rows);
    Ok(OutputSet::write_one(
        dir,
        &shard.file_name(stem),
        csv.as_bytes(),
    )?)
}
