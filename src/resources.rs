//! The memory a run will take, checked before it starts: a command's
//! workload estimated from the sizes its inputs ask for, against a limit
//! (the input files' own size cap is [`crate::input`]'s).
//!
//! The estimates are linear fits, rounded up, of the peak resident memory
//! measured on this project's scenes (2-core machine, release build):
//!
//! | command | measured | estimate |
//! |---|---|---|
//! | `mesh` | 13 / 34 / 125 MB at 7.6k / 29k / 115k nodes | 16 MB + 1.2 kB/node |
//! | `optimize` | 32 / 101 / 392 MB at the same sizes | 32 MB + 3.6 kB/node |
//! | `design` | 197 / 610 MB at 7.6k / 29k nodes | 100 MB + 21 kB/node |
//! | `frame` | 134 MB / 1.14 / 10.5 GB at 1e4 / 1e5 / 1e6 elements | 20 MB + 12 kB/element |
//!
//! (super-60m with 14, 28 and 56 rings; the cantilever benchmark with 1e4 and
//! 1e5 elements, and ten such cantilevers of 1e5 elements each: the frame
//! file's maximum, 41 s). Commands that run several designs at once (`front`,
//! `study`) multiply by the worker threads.

use std::sync::atomic::{AtomicU64, Ordering};

use crate::scene::Scene;

/// The memory limit, bytes; 0: the machine's available memory.
static LIMIT: AtomicU64 = AtomicU64::new(0);

/// The last workload checked and the limit it was checked against, bytes
/// (0: none yet): what an allocation that fails later is compared with.
static CHECKED: [AtomicU64; 2] = [AtomicU64::new(0), AtomicU64::new(0)];

/// A workload that would not fit.
#[derive(Debug, thiserror::Error)]
#[error(
    "{key} asks for about {} of memory ({what}), more than the {} {}: \
     nothing was computed; lower it, or raise the limit with --max-memory",
    bytes_text(*.estimate),
    bytes_text(*.limit),
    if *.machine { "this machine has available" } else { "allowed by --max-memory" }
)]
pub struct MemoryError {
    /// The input that sets the size (`front_net.rings`, `--points`, …).
    pub key: String,
    /// What the estimate covers.
    pub what: String,
    /// The estimate, bytes.
    pub estimate: u64,
    /// The limit, bytes.
    pub limit: u64,
    /// The limit is the machine's available memory (no `--max-memory`).
    pub machine: bool,
}

/// `bytes` for a reader: `3.5 GB`, `120 MB`.
fn bytes_text(bytes: u64) -> String {
    let b = bytes as f64;
    if b >= 1e9 {
        format!("{:.1} GB", b / 1e9)
    } else {
        format!("{:.0} MB", (b / 1e6).max(1.0))
    }
}

/// Keeps the memory a run frees for its next allocations instead of
/// handing it back to the system (glibc only; elsewhere a no-op). glibc
/// serves every allocation above its mmap threshold (128 kB, rising to at
/// most 32 MB) from a fresh mapping and unmaps it when freed, so each of
/// the interior point's and the assembly's per-iteration vectors and
/// factors faulted all its pages in again: `ringmesh design
/// problems/super-100m.toml` spent 10.6 s of 57.6 s in the kernel (3.9 M
/// page faults). Served from the heap and kept there, it takes 3.5 s of
/// 48.2 s, its peak resident memory 1.72 → 1.81 GB. Called once, by a
/// program at its start (the command line does); a library leaves its
/// host's allocator alone.
pub fn retain_freed_memory() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: mallopt only sets allocator parameters; called before any
    // other thread allocates.
    unsafe {
        libc::mallopt(libc::M_MMAP_MAX, 0);
        libc::mallopt(libc::M_TRIM_THRESHOLD, i32::MAX);
    }
}

/// Sets the memory limit (`None`: the machine's available memory).
pub fn set_memory_limit(bytes: Option<u64>) {
    LIMIT.store(bytes.unwrap_or(0), Ordering::Relaxed);
}

/// The machine's available memory (`MemAvailable` of `/proc/meminfo`), bytes.
pub fn available_memory() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

/// Refuses a workload of `estimate` bytes set by `key` beyond the limit.
///
/// # Errors
/// [`MemoryError`] naming `key`, the estimate and the limit.
pub fn check_memory(key: &str, what: &str, estimate: u64) -> Result<(), MemoryError> {
    let set = LIMIT.load(Ordering::Relaxed);
    let (limit, machine) = match set {
        0 => match available_memory() {
            Some(available) => (available, true),
            None => return Ok(()),
        },
        set => (set, false),
    };
    CHECKED[0].store(estimate, Ordering::Relaxed);
    CHECKED[1].store(limit, Ordering::Relaxed);
    if estimate > limit {
        return Err(MemoryError {
            key: key.to_string(),
            what: what.to_string(),
            estimate,
            limit,
            machine,
        });
    }
    Ok(())
}

/// For a message about an allocation that failed: the guard's last
/// estimate against its limit, and whether it was near (above half of it),
/// e.g. `the run was estimated at 3.1 GB of the 3.5 GB available: near the
/// limit`; empty before any check.
pub fn memory_note() -> String {
    let (estimate, limit) = (
        CHECKED[0].load(Ordering::Relaxed),
        CHECKED[1].load(Ordering::Relaxed),
    );
    if estimate == 0 || limit == 0 {
        return String::new();
    }
    format!(
        " (the run was estimated at about {} of the {} limit{})",
        bytes_text(estimate),
        bytes_text(limit),
        if 2 * estimate > limit {
            ": near it, the estimate is too low for this input"
        } else {
            "; the machine had less to give than it said"
        }
    )
}

/// Nodes of a scene's network (front, rear; the ties add none), before it
/// is built.
pub fn scene_nodes(scene: &Scene) -> u64 {
    let (bays, rings) = (scene.truss.bays as u64, scene.front_net.rings as u64);
    2 * (1 + bays.saturating_mul(rings).saturating_mul(rings + 1) / 2)
}

/// Memory of one command's workload on `scene`, bytes (see the module
/// documentation).
pub fn scene_memory(scene: &Scene, command: SceneCommand) -> u64 {
    net_memory(scene_nodes(scene), command)
}

/// Memory of one command's workload on a net of `nodes` nodes, bytes: the
/// one estimate behind [`scene_memory`] and [`network_memory`] (see the
/// module documentation).
pub fn net_memory(nodes: u64, command: SceneCommand) -> u64 {
    let (base, per_node) = match command {
        SceneCommand::Mesh => (16 << 20, 1_200),
        SceneCommand::Optimize | SceneCommand::Truss => (32 << 20, 3_600),
        SceneCommand::Design => (100 << 20, 21_000),
    };
    base + nodes.saturating_mul(per_node)
}

/// Memory of one command's workload on an interchange-format network of
/// `nodes` nodes and `edges` cables, bytes: [`net_memory`] of the nodes,
/// or of a third of the cables when they are more (a reflector net has
/// about three cables a node; a denser graph costs as its cables do).
pub fn network_memory(nodes: u64, edges: u64, command: SceneCommand) -> u64 {
    net_memory(nodes.max(edges / 3), command)
}

/// The workloads [`scene_memory`] estimates.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SceneCommand {
    /// Building and writing the network (`mesh`; `fdm`'s one solve).
    Mesh,
    /// One uniformity solve (`optimize`, `uniformity`).
    Optimize,
    /// The net built and solved once for its pull on the truss (`truss`):
    /// as [`SceneCommand::Optimize`], the truss's few elements aside.
    Truss,
    /// The outer loop, its verification and limit search.
    Design,
}

/// Checks `command`'s workload on an interchange-format network read from
/// `path` ([`network_memory`]), naming the file and its size.
///
/// # Errors
/// [`MemoryError`].
pub fn check_network(
    path: &std::path::Path,
    nodes: usize,
    edges: usize,
    command: SceneCommand,
) -> Result<(), MemoryError> {
    check_memory(
        &path.display().to_string(),
        &format!("{nodes} nodes, {edges} cables"),
        network_memory(nodes as u64, edges as u64, command),
    )
}

/// Checks `command`'s workload on `scene` with the refusal naming `key`
/// before the net (an aperture of a sweep, say: `--apertures 1000`).
///
/// # Errors
/// [`MemoryError`].
pub fn check_scene_for(scene: &Scene, command: SceneCommand, key: &str) -> Result<(), MemoryError> {
    check_scene_as(scene, command, 1, None).map_err(|mut e| {
        e.key = format!("{key}: {}", e.key);
        e
    })
}

/// Checks a frame of `elements` elements ([`frame_memory`]), naming `key`.
///
/// # Errors
/// [`MemoryError`].
pub fn check_frame(key: &str, elements: usize) -> Result<(), MemoryError> {
    check_memory(
        key,
        &format!("{elements} elements"),
        frame_memory(elements as u64),
    )
}

/// Checks `command`'s workload on `scene`, naming `front_net.rings`;
/// `parallel` designs at once (the machine's threads).
///
/// # Errors
/// [`MemoryError`].
pub fn check_scene(scene: &Scene, command: SceneCommand, parallel: u64) -> Result<(), MemoryError> {
    check_scene_as(scene, command, parallel, None)
}

/// [`check_scene`] for `jobs` designs at once set by the `--jobs` option,
/// which the refusal then names with the net.
///
/// # Errors
/// [`MemoryError`].
pub fn check_scene_jobs(
    scene: &Scene,
    command: SceneCommand,
    jobs: u64,
) -> Result<(), MemoryError> {
    check_scene_as(scene, command, jobs, Some("--jobs"))
}

fn check_scene_as(
    scene: &Scene,
    command: SceneCommand,
    parallel: u64,
    parallel_key: Option<&str>,
) -> Result<(), MemoryError> {
    let what = format!(
        "{} nodes{}",
        scene_nodes(scene),
        if parallel > 1 {
            format!(", {parallel} designs at once")
        } else {
            String::new()
        }
    );
    // What the user can lower: the net, and the option that runs designs
    // at once.
    let key = format!(
        "front_net.rings = {} with truss.bays = {}{}",
        scene.front_net.rings,
        scene.truss.bays,
        match parallel_key {
            Some(k) if parallel > 1 => format!(" and {k} {parallel}"),
            _ => String::new(),
        }
    );
    check_memory(
        &key,
        &what,
        scene_memory(scene, command).saturating_mul(parallel.max(1)),
    )
}

/// Memory of a frame of `elements` elements, bytes.
pub fn frame_memory(elements: u64) -> u64 {
    (20 << 20) + elements.saturating_mul(12_000)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn estimates_cover_the_measured_peaks() {
        // super-60m (36 bays) at 14 / 28 / 56 rings: measured peaks, bytes.
        let mut scene = Scene::read(std::path::Path::new("problems/super-60m.toml")).unwrap();
        let measured = [
            (14, 13_312e3, 31_848e3, Some(196_888e3)),
            (28, 34_008e3, 100_808e3, Some(610_452e3)),
            (56, 124_672e3, 392_352e3, None),
        ];
        for (rings, mesh, optimize, design) in measured {
            scene.front_net.rings = rings;
            for (command, peak) in [
                (SceneCommand::Mesh, Some(mesh)),
                (SceneCommand::Optimize, Some(optimize)),
                (SceneCommand::Design, design),
            ] {
                let Some(peak) = peak else { continue };
                let estimate = scene_memory(&scene, command) as f64;
                assert!(
                    (1.0..2.0).contains(&(estimate / peak)),
                    "{rings} rings, {command:?}: {estimate:e} for {peak:e}"
                );
            }
        }
        for (elements, peak) in [(1e4, 134_052e3), (1e5, 1_141_656e3), (1e6, 10_237_708e3)] {
            let estimate = frame_memory(elements as u64) as f64;
            assert!((1.0..2.0).contains(&(estimate / peak)), "{elements}");
        }
    }

    #[test]
    fn a_workload_beyond_the_limit_is_refused_naming_its_key() {
        set_memory_limit(Some(1 << 30));
        let e = check_memory("front_net.rings = 815", "4 M nodes", 3 << 30).unwrap_err();
        // An allocation failing after this check is compared with it.
        let note = memory_note();
        assert!(
            note.contains("3.2 GB of the 1.1 GB limit: near it"),
            "{note}"
        );
        set_memory_limit(None);
        let text = e.to_string();
        assert!(
            text.contains("front_net.rings = 815") && text.contains("3.2 GB"),
            "{text}"
        );
        assert!(text.contains("--max-memory"), "{text}");
    }
}
