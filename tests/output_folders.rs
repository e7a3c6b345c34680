//! Output folders (issue 40 items 1–4): `-o` of the single-file commands
//! names a file or a folder by one rule and never replaces a folder; a
//! folder that holds a mount point is refused before computing and one that
//! is a mount point is written; a folder this user may not write is refused
//! before computing, naming it, never replaced. (The swap keeping files of
//! other writers: `report::output_set`'s unit tests.)

mod common;

use std::os::unix::fs::{MetadataExt, PermissionsExt};
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn names(dir: &Path) -> Vec<String> {
    common::snapshot(dir).into_iter().map(|(n, _)| n).collect()
}

fn frame_file() -> String {
    common::problem("frames/cantilever-moment.toml")
        .to_string_lossy()
        .into_owned()
}

/// Issue 40 item 1: `frame -o K` onto a folder holding a file writes the
/// frame's set into it and keeps the file (it used to become the JSON file,
/// the folder gone); `frame -o D/x.json` writes `x.json` and its path files
/// `x-path.*` into `D` without swapping `D`; a path with another extension
/// than `.json` is refused before anything is written.
#[test]
fn frame_output_is_a_folder_or_a_file_and_never_replaces_a_folder() {
    let root = tempfile::tempdir().unwrap();
    let k = root.path().join("K");
    std::fs::create_dir(&k).unwrap();
    std::fs::write(k.join("a.txt"), "x").unwrap();
    let o = common::ringmesh(&["frame", &frame_file(), "-o", k.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert_eq!(
        names(&k),
        [
            "a.txt",
            "frame-path.csv",
            "frame-path.png",
            "frame-path.svg",
            "frame.json"
        ]
    );
    assert_eq!(std::fs::read_to_string(k.join("a.txt")).unwrap(), "x");

    let d = root.path().join("D");
    std::fs::create_dir(&d).unwrap();
    std::fs::write(d.join("notes.txt"), "mine").unwrap();
    std::fs::write(d.join("frame-path.csv"), "another run's").unwrap();
    let inode = std::fs::metadata(&d).unwrap().ino();
    let x = d.join("x.json");
    let o = common::ringmesh(&["frame", &frame_file(), "-o", x.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert_eq!(
        names(&d),
        [
            "frame-path.csv",
            "notes.txt",
            "x-path.csv",
            "x-path.png",
            "x-path.svg",
            "x.json"
        ]
    );
    assert_eq!(std::fs::metadata(&d).unwrap().ino(), inode, "D was swapped");
    assert_eq!(
        std::fs::read_to_string(d.join("frame-path.csv")).unwrap(),
        "another run's"
    );
    let json: serde_json::Value = serde_json::from_slice(&std::fs::read(&x).unwrap()).unwrap();
    assert_eq!(json["termination"]["status"], "converged");
    assert!(std::fs::read_to_string(d.join("x-path.csv"))
        .unwrap()
        .starts_with("kind,step,load_factor"));

    let csv = d.join("frame-path.csv");
    let o = common::ringmesh(&["frame", &frame_file(), "-o", csv.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("name a .json file, or a folder"),
        "{}",
        stderr(&o)
    );
    assert_eq!(
        std::fs::read_to_string(&csv).unwrap(),
        "another run's",
        "the refused run wrote"
    );
    assert_eq!(names(root.path()), ["D", "K"]);
}

/// Issue 40 item 1: `fdm`, `uniformity` and `cantilever` write into a
/// folder `-o` names under their default names, beside what it holds.
#[test]
fn single_file_commands_write_into_a_folder_beside_its_files() {
    let root = tempfile::tempdir().unwrap();
    let out = root.path().join("out");
    std::fs::create_dir(&out).unwrap();
    std::fs::write(out.join("a.txt"), "x").unwrap();
    let network = common::reference_path();
    let o = common::ringmesh(&[
        "fdm",
        network.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let o = common::ringmesh(&[
        "uniformity",
        network.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let o = common::ringmesh(&["cantilever", "--elements", "2", "-o", out.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert_eq!(
        names(&out),
        ["a.txt", "cantilever.json", "fdm.json", "uniformity.json"]
    );
    let fdm: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("fdm.json")).unwrap()).unwrap();
    assert!(fdm["max_residual"].as_f64().unwrap() < 1e-6);
    // A file where a folder is named: refused before computing.
    let o = common::ringmesh(&[
        "fdm",
        network.to_str().unwrap(),
        "-o",
        out.join("a.txt/f.json").to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("is a file, not a folder"),
        "{}",
        stderr(&o)
    );
    assert_eq!(names(root.path()), ["out"]);
}

/// Runs the binary as the unprivileged user `nobody` when this process is
/// root (a root process may write anywhere), else as this user; `None`
/// when it cannot (no `setpriv`).
fn ringmesh_unprivileged(args: &[&str]) -> Option<Output> {
    // SAFETY: `geteuid` has no preconditions.
    let root = unsafe { libc::geteuid() } == 0;
    let mut command = if root {
        let mut c = Command::new("setpriv");
        c.args(["--reuid=65534", "--regid=65534", "--clear-groups"])
            .arg(env!("CARGO_BIN_EXE_ringmesh"));
        c
    } else {
        Command::new(env!("CARGO_BIN_EXE_ringmesh"))
    };
    match command.args(args).output() {
        Ok(o) if o.status.code() != Some(127) && !stderr(&o).contains("setpriv:") => Some(o),
        Ok(o) => {
            eprintln!("skipped: cannot run as another user: {}", stderr(&o));
            None
        }
        Err(e) => {
            eprintln!("skipped: cannot run as another user: {e}");
            None
        }
    }
}

/// A scratch folder any user may enter, with small-hex's scene in it.
fn open_scratch() -> (tempfile::TempDir, PathBuf) {
    let root = tempfile::tempdir().unwrap();
    std::fs::set_permissions(root.path(), std::fs::Permissions::from_mode(0o755)).unwrap();
    let scene = root.path().join("small-hex.toml");
    std::fs::copy(common::problem("small-hex.toml"), &scene).unwrap();
    std::fs::set_permissions(&scene, std::fs::Permissions::from_mode(0o644)).unwrap();
    (root, scene)
}

/// Issue 40 item 4: a folder this user may not write (mode 555, another
/// user's) is refused before computing (exit 2), naming it, and left as it
/// was — by a set (`mesh`) and by a single-file command (`fdm`); a folder
/// above it that may not be written (where the set is staged) is refused
/// naming the `-o` folder, not the staging folder (item 9).
#[test]
fn a_folder_this_user_may_not_write_is_refused_naming_it() {
    let (root, scene) = open_scratch();
    let x = root.path().join("X");
    std::fs::create_dir(&x).unwrap();
    std::fs::write(x.join("a.txt"), "x").unwrap();
    std::fs::set_permissions(&x, std::fs::Permissions::from_mode(0o555)).unwrap();
    let inode = std::fs::metadata(&x).unwrap().ino();
    let Some(o) =
        ringmesh_unprivileged(&["mesh", scene.to_str().unwrap(), "-o", x.to_str().unwrap()])
    else {
        return;
    };
    let why = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{why}");
    let named = format!("cannot write into the output folder {}", x.display());
    assert!(
        why.contains(&named) && why.contains("permission denied"),
        "{why}"
    );
    let network = common::reference_path();
    let fdm = x.join("f.json");
    let o = ringmesh_unprivileged(&[
        "fdm",
        network.to_str().unwrap(),
        "-o",
        fdm.to_str().unwrap(),
    ])
    .unwrap();
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(
        stderr(&o).contains(&x.display().to_string()),
        "{}",
        stderr(&o)
    );
    assert_eq!(std::fs::metadata(&x).unwrap().ino(), inode, "replaced");
    assert_eq!(names(&x), ["a.txt"]);
    std::fs::set_permissions(&x, std::fs::Permissions::from_mode(0o755)).unwrap();

    // The folder above may not be written: the new set cannot be made there.
    let parent = root.path().join("P");
    let y = parent.join("Y");
    std::fs::create_dir_all(&y).unwrap();
    std::fs::set_permissions(&y, std::fs::Permissions::from_mode(0o777)).unwrap();
    std::fs::set_permissions(&parent, std::fs::Permissions::from_mode(0o555)).unwrap();
    // SAFETY: `chown` on a path this test made; `geteuid` has no preconditions.
    if unsafe { libc::geteuid() } == 0 {
        // Y is nobody's own, so that a swap would be the way.
        let c = std::ffi::CString::new(y.to_str().unwrap()).unwrap();
        assert_eq!(unsafe { libc::chown(c.as_ptr(), 65534, 65534) }, 0);
    }
    let o = ringmesh_unprivileged(&["mesh", scene.to_str().unwrap(), "-o", y.to_str().unwrap()])
        .unwrap();
    let why = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{why}");
    let named = format!("cannot write into the output folder {}", y.display());
    assert!(why.contains(&named), "{why}");
    assert!(!why.contains(".staging-"), "{why}");
    assert!(names(&y).is_empty());
    std::fs::set_permissions(&parent, std::fs::Permissions::from_mode(0o755)).unwrap();
}

/// Issue 40 item 4: another user's folder that this user may write (mode
/// 777) is written in place — the files renamed into it — never replaced by
/// a folder this user owns.
#[test]
fn another_users_writable_folder_is_written_in_place() {
    // SAFETY: `geteuid` has no preconditions.
    if unsafe { libc::geteuid() } != 0 {
        eprintln!("skipped: needs root to make a folder of another user");
        return;
    }
    let (root, scene) = open_scratch();
    let x = root.path().join("X");
    std::fs::create_dir(&x).unwrap();
    std::fs::write(x.join("a.txt"), "x").unwrap();
    std::fs::set_permissions(&x, std::fs::Permissions::from_mode(0o777)).unwrap();
    let inode = std::fs::metadata(&x).unwrap().ino();
    let Some(o) =
        ringmesh_unprivileged(&["mesh", scene.to_str().unwrap(), "-o", x.to_str().unwrap()])
    else {
        return;
    };
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let m = std::fs::metadata(&x).unwrap();
    assert_eq!((m.ino(), m.uid()), (inode, 0), "replaced");
    assert_eq!(names(&x), ["a.txt", "mesh.vtu", "network.json"]);
    assert_eq!(names(root.path()), ["X", "small-hex.toml"]);
}

/// A tmpfs mounted at a path for the life of the value (unmounted on drop).
struct Mount(PathBuf);

impl Mount {
    /// Mounts a tmpfs at `at`, or says why not (not root, no mount).
    fn tmpfs(at: &Path) -> Option<Mount> {
        std::fs::create_dir_all(at).unwrap();
        let o = Command::new("mount")
            .args(["-t", "tmpfs", "ringmesh-test", at.to_str().unwrap()])
            .output();
        match o {
            Ok(o) if o.status.success() => Some(Mount(at.to_path_buf())),
            Ok(o) => {
                eprintln!("skipped: cannot mount a tmpfs: {}", stderr(&o));
                None
            }
            Err(e) => {
                eprintln!("skipped: cannot mount a tmpfs: {e}");
                None
            }
        }
    }
}

impl Drop for Mount {
    fn drop(&mut self) {
        let _ = Command::new("umount").arg(&self.0).status();
    }
}

/// Issue 40 item 2: a folder holding a mount point is refused before
/// computing (exit 2, naming the mount point), and what is mounted stays
/// where it is, with nothing left beside the folder; a folder that is itself
/// a mount point (a container's volume) is written, in place, keeping what
/// it holds.
#[test]
fn mount_points_are_refused_inside_and_written_into_when_they_are_the_folder() {
    let root = tempfile::tempdir().unwrap();
    let scene = common::problem_arg("small-hex.toml");
    let x = root.path().join("X");
    let Some(mount) = Mount::tmpfs(&x.join("m")) else {
        return;
    };
    std::fs::write(x.join("m/mounted.txt"), "on the tmpfs").unwrap();
    let o = common::ringmesh(&["mesh", &scene, "-o", x.to_str().unwrap()]);
    let why = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{why}");
    assert!(
        why.contains("holds a mount point") && why.contains(&x.join("m").display().to_string()),
        "{why}"
    );
    assert_eq!(
        std::fs::read_to_string(x.join("m/mounted.txt")).unwrap(),
        "on the tmpfs"
    );
    assert_eq!(names(&x), ["m"]);
    assert_eq!(names(root.path()), ["X"]);
    drop(mount);

    let v = root.path().join("V");
    let Some(_volume) = Mount::tmpfs(&v) else {
        return;
    };
    std::fs::write(v.join("kept.txt"), "kept").unwrap();
    let device = std::fs::metadata(&v).unwrap().dev();
    for _ in 0..2 {
        let o = common::ringmesh(&["mesh", &scene, "-o", v.to_str().unwrap()]);
        assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    }
    assert_eq!(std::fs::metadata(&v).unwrap().dev(), device);
    assert_eq!(names(&v), ["kept.txt", "mesh.vtu", "network.json"]);
    assert_eq!(names(root.path()), ["V", "X"]);
}
