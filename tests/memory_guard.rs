//! Every command's workload is estimated and checked against `--max-memory`
//! before it computes or writes anything (issue 40 item 5): refused with
//! exit 2, naming what sets the size, with the same estimate `design` is
//! refused by; and an allocation that fails is said to be memory.

mod common;

use std::path::Path;

/// Runs `args` under `--max-memory limit` and returns its exit code and
/// standard error.
fn under(limit: &str, args: &[&str]) -> (Option<i32>, String) {
    let mut all = vec!["--max-memory", limit];
    all.extend_from_slice(args);
    let run = common::ringmesh(&all);
    (
        run.status.code(),
        String::from_utf8_lossy(&run.stderr).into_owned(),
    )
}

fn refused(limit: &str, args: &[&str], needle: &str, output: &Path) {
    let (code, stderr) = under(limit, args);
    assert_eq!(code, Some(2), "{args:?}: {stderr}");
    assert!(
        stderr.contains(needle) && stderr.contains("--max-memory"),
        "{args:?}: expected {needle:?} in {stderr}"
    );
    assert!(!output.exists(), "{args:?} left {}", output.display());
}

/// The aperture study checks each aperture's own design, the estimate
/// `design` is refused by: at 64M an aperture of the scene's own size is
/// refused as `design` is, and a 1000 m aperture at 1G (≈ 32 GB) names it.
#[test]
fn the_aperture_study_checks_each_aperture_as_design_does() {
    let dir = tempfile::tempdir().unwrap();
    let scene = common::problem_arg("small-hex.toml");
    let out = dir.path().join("ap");
    let o = out.to_str().unwrap();
    let (code, design) = under("64M", &["design", &scene, "-o", o]);
    assert_eq!(code, Some(2), "{design}");
    refused(
        "64M",
        &["apertures", &scene, "--apertures", "6", "-o", o],
        "--apertures 6: front_net.rings = 3",
        &out,
    );
    // The same estimate as design's: the same bytes named.
    let (_, aperture) = under("64M", &["apertures", &scene, "--apertures", "6", "-o", o]);
    let estimate = |text: &str| {
        text.split("asks for about ")
            .nth(1)
            .map(|t| t[..8].to_string())
    };
    assert_eq!(
        estimate(&design),
        estimate(&aperture),
        "{design}\n{aperture}"
    );
    refused(
        "1G",
        &["apertures", &scene, "--apertures", "6,1000", "-o", o],
        "--apertures 1000: front_net.rings = 500",
        &out,
    );
}

/// `truss` with a net beyond memory is refused up front, not after half a
/// minute as "not positive definite".
#[test]
fn truss_with_many_rings_is_refused_up_front() {
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(common::problem("small-hex.toml")).unwrap();
    let scene = dir.path().join("big.toml");
    std::fs::write(&scene, text.replace("rings = 3\n", "rings = 800\n")).unwrap();
    let out = dir.path().join("t.json");
    refused(
        "1G",
        &[
            "truss",
            scene.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
        ],
        "front_net.rings = 800",
        &out,
    );
}

/// `fdm`, `uniformity` and `cantilever` check their sizes too: the network
/// file (its nodes and cables) and the cantilever's elements are named.
#[test]
fn fdm_uniformity_and_cantilever_are_checked() {
    let dir = tempfile::tempdir().unwrap();
    let network = common::reference_path();
    let net = network.to_str().unwrap();
    let out = dir.path().join("o.json");
    let o = out.to_str().unwrap();
    refused("1M", &["fdm", net, "-o", o], net, &out);
    refused("1M", &["uniformity", net, "-o", o], net, &out);
    let folder = dir.path().join("c");
    refused(
        "1M",
        &[
            "cantilever",
            "--elements",
            "10",
            "-o",
            folder.to_str().unwrap(),
        ],
        "--elements 10",
        &folder,
    );
    // And they run under a limit that holds them.
    let (code, stderr) = under("1G", &["fdm", net, "-o", o]);
    assert_eq!(code, Some(0), "{stderr}");
}

/// One estimate: a network file costs what the scene's net of as many
/// nodes costs.
#[test]
fn a_network_costs_what_its_scene_costs() {
    use ringmesh::resources::{network_memory, scene_memory, scene_nodes, SceneCommand};
    let scene = common::scene("small-hex");
    let nodes = scene_nodes(&scene);
    for command in [
        SceneCommand::Mesh,
        SceneCommand::Optimize,
        SceneCommand::Design,
    ] {
        assert_eq!(
            network_memory(nodes, 3 * nodes, command),
            scene_memory(&scene, command)
        );
    }
    // A graph far denser than a net costs as its cables do.
    assert!(
        network_memory(10, 3_000_000, SceneCommand::Mesh)
            > network_memory(10, 30, SceneCommand::Mesh)
    );
}
