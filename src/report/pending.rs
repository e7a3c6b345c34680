//! The staging folders and temporary files this process has open, and their
//! removal when a signal ends the run ([`abandon_all_and_exit`]): the
//! registry every writer of the report module creates its files through.

use std::fs::{self, File};
use std::io;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

/// Staging folders and temporary files of this process, removed by
/// [`abandon_all_and_exit`]; also held while a set is swapped in.
static PENDING: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

/// Creates the temporary file `path` (and its folder, if missing),
/// registered for removal on interruption. Registry, folder and file are
/// made under the registry's lock: a signal handler, which holds that lock
/// until the process exits, either finds them all and removes them, or
/// none is created — a folder made after its removal would outlive the run.
pub(super) fn create_registered(path: &Path) -> io::Result<File> {
    let mut pending = lock_pending();
    pending.push(path.to_path_buf());
    let created = (|| {
        if let Some(parent) = path.parent().filter(|p| !p.as_os_str().is_empty()) {
            fs::create_dir_all(parent)?;
        }
        File::create(path)
    })();
    if created.is_err() {
        pending.retain(|p| p != path);
    }
    created
}

/// Forgets `path` (written, renamed or removed).
pub(super) fn unregister(path: &Path) {
    lock_pending().retain(|p| p != path);
}

pub(super) fn lock_pending() -> std::sync::MutexGuard<'static, Vec<PathBuf>> {
    PENDING.lock().unwrap_or_else(|e| e.into_inner())
}

/// Removes every staging folder and temporary file this process has open
/// and exits with `code`: for a signal handler. Waits for a set being
/// swapped in to finish, and holds the registry until the exit, so that no
/// new file or folder is created ([`create_registered`]); a write already
/// under way may still rename or link a file into a folder being removed,
/// so each removal is retried until it holds.
pub fn abandon_all_and_exit(code: i32) -> ! {
    let pending = lock_pending();
    for path in pending.iter() {
        for _ in 0..200 {
            let _ = if path.is_dir() {
                fs::remove_dir_all(path)
            } else {
                fs::remove_file(path)
            };
            if fs::symlink_metadata(path).is_err() {
                break;
            }
            std::thread::sleep(std::time::Duration::from_millis(1));
        }
    }
    std::process::exit(code)
}
