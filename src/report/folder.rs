//! What every ringmesh writer asks of an output folder before it writes:
//! its locks ([`lock_ancestors`], [`lock_folder`]), its permission as the
//! file system would judge it ([`check_writable`]), and the mount points
//! that a folder swap must not carry away ([`mount_points_in`]).
//!
//! The locks are advisory `flock`s on the folders themselves (no lock file
//! is left behind), taken root first, so that no two writers wait on each
//! other in a cycle:
//!
//! - a writer into a folder `D` — one file ([`super::OutputSet::write_one`])
//!   or a set of files — holds a *shared* lock on every folder above `D`
//!   while it writes (a set: for its whole run), so that no folder above it
//!   is swapped away meanwhile;
//! - a set that swaps `D` ([`super::OutputSet`]) holds an *exclusive* lock
//!   on `D` while it prepares and while it swaps: single-file writers into
//!   `D` (a shared lock on `D`) and runs into folders inside `D` (a shared
//!   lock on `D`, as on every folder above them) wait for it, and it for
//!   them.
//!
//! A folder swapped away between opening and locking it is locked anew:
//! each lock is checked against the folder the path names once it is held.

use std::ffi::CString;
use std::fs::{self, File};
use std::io;
use std::os::unix::ffi::OsStrExt;
use std::os::unix::fs::MetadataExt;
use std::path::{Path, PathBuf};

use rustix::fs::FlockOperation;

/// How a folder is locked.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Hold {
    /// Writers into the folder, or into a folder inside it.
    Shared,
    /// A set that swaps the folder; `Wait::No` refuses instead of waiting.
    Exclusive,
}

/// Whether a lock waits for its holder.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Wait {
    Yes,
    No,
}

/// Locks the folder `dir` (which exists): `None` when `Wait::No` finds it
/// held by another writer.
pub(super) fn lock_folder(dir: &Path, hold: Hold, wait: Wait) -> io::Result<Option<File>> {
    let operation = match (hold, wait) {
        (Hold::Shared, Wait::Yes) => FlockOperation::LockShared,
        (Hold::Shared, Wait::No) => FlockOperation::NonBlockingLockShared,
        (Hold::Exclusive, Wait::Yes) => FlockOperation::LockExclusive,
        (Hold::Exclusive, Wait::No) => FlockOperation::NonBlockingLockExclusive,
    };
    loop {
        let folder = File::open(dir)?;
        match rustix::fs::flock(&folder, operation) {
            Ok(()) => {}
            Err(rustix::io::Errno::WOULDBLOCK) => return Ok(None),
            Err(e) => return Err(e.into()),
        }
        let held = folder.metadata()?;
        let now = fs::metadata(dir)?;
        if (held.dev(), held.ino()) == (now.dev(), now.ino()) {
            return Ok(Some(folder));
        }
    }
}

/// Shared locks on every folder above the folder `dir` (an absolute path),
/// root first, waiting for a set that swaps one of them. A folder this
/// process may not open (no read permission) is passed over: no writer
/// that cannot read it swaps it either.
pub(super) fn lock_ancestors(dir: &Path) -> io::Result<Vec<File>> {
    let mut above: Vec<&Path> = dir.ancestors().skip(1).collect();
    above.reverse();
    let mut locks = Vec::with_capacity(above.len());
    for folder in above {
        match lock_folder(folder, Hold::Shared, Wait::Yes) {
            Ok(Some(lock)) => locks.push(lock),
            Ok(None) => unreachable!("a waiting lock is always taken"),
            Err(e) if e.kind() == io::ErrorKind::PermissionDenied => {}
            Err(e) => return Err(e),
        }
    }
    Ok(locks)
}

/// Whether this process may create and remove entries in the folder `dir`,
/// as the file system judges it (`faccessat(W_OK | X_OK, AT_EACCESS)`: the
/// effective user, its groups, a read-only mount).
pub(super) fn may_write_into(dir: &Path) -> bool {
    let Ok(path) = CString::new(dir.as_os_str().as_bytes()) else {
        return false;
    };
    // SAFETY: `path` is a valid NUL-terminated string that outlives the call.
    let code = unsafe {
        libc::faccessat(
            libc::AT_FDCWD,
            path.as_ptr(),
            libc::W_OK | libc::X_OK,
            libc::AT_EACCESS,
        )
    };
    code == 0
}

/// Checks, before any computing, that a run may write into the folder
/// `dir`: when it exists, that it is a folder this process may write into;
/// when not, that the nearest folder above it that exists is one (the
/// folders between are created). Names `dir` and, when the refusal is about
/// a folder above it, that folder.
pub(super) fn check_writable(dir: &Path) -> io::Result<()> {
    let mut at = dir;
    loop {
        match fs::metadata(at) {
            Ok(m) if m.is_dir() => break,
            Ok(_) => {
                return Err(io::Error::new(
                    io::ErrorKind::NotADirectory,
                    if at == dir {
                        "it is a file, not a folder".to_string()
                    } else {
                        format!("{} is a file, not a folder", at.display())
                    },
                ))
            }
            Err(e)
                if matches!(
                    e.kind(),
                    io::ErrorKind::NotFound | io::ErrorKind::NotADirectory
                ) =>
            {
                at = match at.parent() {
                    Some(p) if !p.as_os_str().is_empty() => p,
                    _ => Path::new("."),
                };
            }
            Err(e) => return Err(e),
        }
    }
    if may_write_into(at) {
        return Ok(());
    }
    Err(io::Error::new(
        io::ErrorKind::PermissionDenied,
        if at == dir {
            "permission denied (the folder is not writable by this user)".to_string()
        } else {
            format!(
                "permission denied: {} is not writable by this user",
                at.display()
            )
        },
    ))
}

/// The device a path lies on (`st_dev`, not following a final symbolic link).
pub(super) fn device_of(path: &Path) -> io::Result<u64> {
    Ok(fs::symlink_metadata(path)?.dev())
}

/// Whether the folder `dir` is a mount point: on another device than the
/// folder above it (`device`: [`device_of`], or a stand-in in tests).
pub(super) fn is_mount_point(
    dir: &Path,
    device: &dyn Fn(&Path) -> io::Result<u64>,
) -> io::Result<bool> {
    match dir.parent() {
        Some(parent) => Ok(device(dir)? != device(parent)?),
        None => Ok(true),
    }
}

/// The folders directly in the folder `dir` that are mount points (on
/// another device than `dir`): a folder swap would move what is mounted
/// there. Symbolic links are not followed.
pub(super) fn mount_points_in(
    dir: &Path,
    device: &dyn Fn(&Path) -> io::Result<u64>,
) -> io::Result<Vec<PathBuf>> {
    let own = device(dir)?;
    let mut mounts = Vec::new();
    for entry in fs::read_dir(dir)? {
        let entry = entry?;
        if entry.file_type()?.is_dir() && device(&entry.path())? != own {
            mounts.push(entry.path());
        }
    }
    mounts.sort();
    Ok(mounts)
}

#[cfg(test)]
mod tests {
    use super::super::atomic::write_atomic;
    use super::*;

    #[test]
    fn mount_points_are_the_folders_on_another_device() {
        let root = tempfile::tempdir().unwrap();
        let dir = root.path().join("out");
        for sub in ["a", "m", "b/m2"] {
            fs::create_dir_all(dir.join(sub)).unwrap();
        }
        write_atomic(&dir.join("m.txt"), b"a file").unwrap();
        // A stand-in for st_dev: `m` (and what is below it) on device 2,
        // everything else on device 1.
        let mounted = dir.join("m");
        let device = |p: &Path| -> io::Result<u64> {
            fs::symlink_metadata(p)?;
            Ok(if p.starts_with(&mounted) { 2 } else { 1 })
        };
        assert_eq!(mount_points_in(&dir, &device).unwrap(), [mounted.as_path()]);
        assert!(is_mount_point(&mounted, &device).unwrap());
        assert!(!is_mount_point(&dir, &device).unwrap());
        // A mount point deeper down is not one of `dir`'s own entries: it
        // moves with the folder that holds it.
        assert!(mount_points_in(&dir.join("b"), &device).unwrap().is_empty());
        // The real devices: one file system.
        assert!(mount_points_in(&dir, &device_of).unwrap().is_empty());
    }

    #[test]
    fn a_missing_folder_is_judged_by_the_nearest_folder_above() {
        let root = tempfile::tempdir().unwrap();
        check_writable(&root.path().join("a/b/c")).unwrap();
        let file = root.path().join("f");
        write_atomic(&file, b"x").unwrap();
        let e = check_writable(&file.join("sub")).unwrap_err();
        assert!(e.to_string().contains("is a file"), "{e}");
        let e = check_writable(&file).unwrap_err();
        assert_eq!(e.to_string(), "it is a file, not a folder");
    }

    #[test]
    fn a_shared_lock_excludes_an_exclusive_one_and_not_another_shared() {
        let root = tempfile::tempdir().unwrap();
        let a = lock_folder(root.path(), Hold::Shared, Wait::No).unwrap();
        assert!(a.is_some());
        assert!(lock_folder(root.path(), Hold::Shared, Wait::No)
            .unwrap()
            .is_some());
        assert!(lock_folder(root.path(), Hold::Exclusive, Wait::No)
            .unwrap()
            .is_none());
        drop(a);
        assert!(lock_folder(root.path(), Hold::Exclusive, Wait::No)
            .unwrap()
            .is_some());
    }
}
