//! A command's output files as one set: all of them or none, and no file
//! the command did not write ever taken away.
//!
//! [`OutputSet::begin`] runs before any computing: it checks that this user
//! may write into the target folder as the file system would judge it
//! (refusing, naming the folder), creates it, refuses a folder that holds a
//! mount point (a swap would carry what is mounted there away), takes the
//! locks of `folder.rs` (shared on every folder above the target for the
//! whole run), refuses a second set into the same folder (naming it),
//! removes what killed runs left, and creates a staging folder. The command
//! writes its files into the staging folder; [`OutputSet::commit`] then
//! publishes them, in one of two ways:
//!
//! - **Swap** (the run's own folder): the staging folder, beside the target,
//!   is given every other entry of the target — files as hard links,
//!   symbolic links recreated, folders as empty stand-ins — and the two are
//!   exchanged with one atomic `renameat2(RENAME_EXCHANGE)`; each folder the
//!   target held is then exchanged back into it (the folder itself: its
//!   inode, what is mounted below it, what a process has open in it stay),
//!   and whatever a writer that takes no lock put into the old folder
//!   meanwhile is moved into the new one. The old folder is removed only
//!   once it is empty (`rmdir`, retried), so nothing is removed with it that
//!   the run did not write. Every ringmesh writer takes the target's lock,
//!   so none writes during the swap. A reader, or a run killed at any
//!   moment, sees the previous complete set or the new one, never a mix.
//! - **In place** (a target that is a mount point and cannot be renamed, a
//!   folder owned by another user, which a swap would replace by one this
//!   user owns, and the files written beside an output file,
//!   [`OutputSet::begin_beside`]): the staging folder is inside the target
//!   (`.staging-RUN`) and each file is renamed into the target, JSON last,
//!   under the target's lock. Each file is whole; a reader at the moment of
//!   the renames may see files of two runs, which the run's manifest in its
//!   JSON finds out ([`check_manifest`]).
//!
//! What a run killed with SIGKILL leaves is its staging folder
//! (`.NAME.staging-RUN` beside the target, `.staging-RUN` in it), never a
//! file in the target; the next set into the same folder removes it (giving
//! back to the target any folder of it the staging folder holds). SIGINT
//! and SIGTERM remove it at once ([`super::abandon_all_and_exit`], which the
//! CLI's signal handler calls, and which waits for a set being published),
//! with every temporary file [`super::write_atomic`] has open (`pending.rs`).

use std::ffi::OsString;
use std::fs::{self, File};
use std::io;
use std::os::unix::fs::MetadataExt;
use std::path::{Path, PathBuf};
use std::time::{Duration, SystemTime, UNIX_EPOCH};

use serde::Serialize;

use super::atomic::write_atomic;
use super::error::ReportError;
use super::folder::{
    check_writable, device_of, is_mount_point, lock_ancestors, lock_folder, may_write_into,
    mount_points_in, Hold, Wait,
};
use super::pending::{lock_pending, unregister};

/// Longest file name most file systems take, bytes.
const NAME_MAX: usize = 255;

/// The name of an in-place staging folder, before the run's identifier.
const IN_PLACE_PREFIX: &str = ".staging-";

/// How many times the old folder of a swap is emptied of what writers that
/// take no lock keep adding to it before it is left (and named).
const EMPTYING_ROUNDS: usize = 1000;

/// A run's JSON report with its [`RunRecord`] first (`"run": {…}`).
#[derive(Serialize)]
pub struct WithRun<'a, T: Serialize> {
    /// The run's identifier and files.
    pub run: &'a RunRecord,
    /// The report.
    #[serde(flatten)]
    pub report: &'a T,
}

/// A new run's identifier: time and process, unique on one machine.
fn new_run_id() -> String {
    let now = SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .unwrap_or_default();
    format!(
        "{}-{:09}-{}",
        now.as_secs(),
        now.subsec_nanos(),
        std::process::id()
    )
}

/// How a set reaches its target folder (see the module's documentation).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Placement {
    Swap,
    InPlace,
}

/// The files of one run of one command, written into a staging folder and
/// published into the target folder as one.
#[derive(Debug)]
pub struct OutputSet {
    target: PathBuf,
    staging: PathBuf,
    names: Vec<String>,
    run_id: String,
    placement: Placement,
    /// Shared locks on every folder above the target, held while the set lives.
    _above: Vec<File>,
    /// The staging folder's own lock: the set is alive while it is held (a
    /// staging folder nobody holds was left by a killed run).
    _alive: File,
    committed: bool,
    /// Whether this run created the target folder: a refusal after `begin`
    /// then leaves no empty folder behind.
    created: bool,
}

/// Times [`OutputSet::begin`] looks again for a folder that a set swapping
/// a folder above it took away for a moment (1 ms apart).
const SWAP_RETRIES: usize = 1000;

impl OutputSet {
    /// Prepares a set of the files `names` in the folder `dir` (created if
    /// needed), swapped in as one: checks the names and the permission,
    /// locks, removes what killed runs left, creates the staging folder.
    ///
    /// # Errors
    /// [`ReportError::Name`] for a name that is not a plain file name,
    /// [`ReportError::Unwritable`] when the folder, or the folder above it
    /// where the set is staged, may not be written by this user,
    /// [`ReportError::MountPoint`] when a folder in it is a mount point,
    /// [`ReportError::Busy`] when another set is being written into it.
    pub fn begin(dir: &Path, names: &[&str]) -> Result<OutputSet, ReportError> {
        Self::prepare(dir, names, false)
    }

    /// Prepares a set of the files `names` written beside other files in the
    /// folder `dir` (the folder of an output file, `frame -o D/x.json`):
    /// the folder is never swapped; each file is renamed into it.
    ///
    /// # Errors
    /// As [`OutputSet::begin`], but for mount points, which do not matter here.
    pub fn begin_beside(dir: &Path, names: &[&str]) -> Result<OutputSet, ReportError> {
        Self::prepare(dir, names, true)
    }

    fn prepare(dir: &Path, names: &[&str], beside: bool) -> Result<OutputSet, ReportError> {
        for name in names {
            check_name(name)?;
        }
        // Until `prepare_once` holds the locks above `dir`, a set swapping a
        // folder above it can take that folder away for a moment (between
        // its two renames, `X/sub` is not there): a missing folder is looked
        // for again. Without this, `begin("X/sub")` beside a set swapping
        // `X` failed with `NotFound` in
        // `sets_into_a_folder_and_a_folder_in_it_never_take_each_others_files`
        // (once, in a full test run on a loaded machine).
        let mut attempts = 0;
        loop {
            match Self::prepare_once(dir, names, beside) {
                Err(ReportError::Unwritable { ref source, .. })
                    if source.kind() == io::ErrorKind::NotFound && attempts < SWAP_RETRIES =>
                {
                    attempts += 1;
                    std::thread::sleep(Duration::from_millis(1));
                }
                prepared => return prepared,
            }
        }
    }

    fn prepare_once(dir: &Path, names: &[&str], beside: bool) -> Result<OutputSet, ReportError> {
        check_writable(dir).map_err(unwritable_at(dir))?;
        // Created by this run only if this run's `mkdir` made it: two runs
        // starting together both find it missing, and one of them creates it.
        if let Some(parent) = dir.parent().filter(|p| !p.as_os_str().is_empty()) {
            fs::create_dir_all(parent).map_err(unwritable_at(dir))?;
        }
        let created = match fs::create_dir(dir) {
            Ok(()) => true,
            Err(e) if e.kind() == io::ErrorKind::AlreadyExists => false,
            Err(e) => return Err(unwritable_at(dir)(e)),
        };
        let prepared = Self::prepare_created(dir, names, beside, created);
        // A refusal leaves no folder it made — except when another run
        // holds it (`Busy`): that run writes into it, and stages beside it
        // until then, so it is empty and still that run's target.
        if matches!(prepared, Err(ref e) if !matches!(e, ReportError::Busy { .. })) && created {
            let _ = fs::remove_dir(dir);
        }
        prepared
    }

    fn prepare_created(
        dir: &Path,
        names: &[&str],
        beside: bool,
        created: bool,
    ) -> Result<OutputSet, ReportError> {
        let target = fs::canonicalize(dir).map_err(unwritable_at(dir))?;
        let (Some(parent), Some(folder)) = (target.parent(), target.file_name()) else {
            return Err(ReportError::Unwritable {
                path: target.clone(),
                source: io::Error::new(
                    io::ErrorKind::InvalidInput,
                    "the file system's root cannot hold a run's outputs",
                ),
            });
        };
        let above = lock_ancestors(&target).map_err(unwritable_at(&target))?;
        let lock = lock_folder(&target, Hold::Exclusive, Wait::Yes)
            .map_err(unwritable_at(&target))?
            .expect("a waiting lock is always taken");
        if !may_write_into(&target) {
            return Err(ReportError::Unwritable {
                path: target.clone(),
                source: io::Error::new(
                    io::ErrorKind::PermissionDenied,
                    "permission denied (the folder is not writable by this user)",
                ),
            });
        }
        let metadata = fs::metadata(&target).map_err(unwritable_at(&target))?;
        // SAFETY: `geteuid` has no preconditions and cannot fail.
        let owned = metadata.uid() == unsafe { libc::geteuid() };
        let mount_point = is_mount_point(&target, &device_of).map_err(unwritable_at(&target))?;
        let placement = if beside || mount_point || !owned {
            Placement::InPlace
        } else {
            Placement::Swap
        };
        if placement == Placement::Swap {
            if !may_write_into(parent) {
                return Err(ReportError::Unwritable {
                    path: target.clone(),
                    source: io::Error::new(
                        io::ErrorKind::PermissionDenied,
                        format!(
                            "permission denied on the folder above it, {}, where the new \
                             set is made before it is swapped in",
                            parent.display()
                        ),
                    ),
                });
            }
            check_no_mount_points(&target)?;
        }
        let beside_prefix = format!(".{}.staging-", folder.to_string_lossy());
        for (place, prefix) in [
            (parent, beside_prefix.as_str()),
            (target.as_path(), IN_PLACE_PREFIX),
        ] {
            let Ok(entries) = fs::read_dir(place) else {
                continue;
            };
            for entry in entries.flatten() {
                if !entry.file_name().to_string_lossy().starts_with(prefix) {
                    continue;
                }
                match lock_folder(&entry.path(), Hold::Exclusive, Wait::No) {
                    Ok(None) => {
                        return Err(ReportError::Busy {
                            path: target.clone(),
                        })
                    }
                    Ok(Some(_left)) if place == parent => {
                        remove_left_staging(&entry.path(), &target)
                    }
                    Ok(Some(_left)) => {
                        let _ = fs::remove_dir_all(entry.path());
                    }
                    Err(_) => {}
                }
            }
        }
        let run_id = new_run_id();
        let staging = match placement {
            Placement::Swap => parent.join(format!("{beside_prefix}{run_id}")),
            Placement::InPlace => target.join(format!("{IN_PLACE_PREFIX}{run_id}")),
        };
        // Registered and created under the registry's lock, as in
        // `create_registered`; locked before the target's lock is let go,
        // so that no other set finds it unlocked.
        let alive = {
            let mut pending = lock_pending();
            if let Err(e) = fs::create_dir(&staging) {
                return Err(unwritable_at(&target)(e));
            }
            pending.push(staging.clone());
            match lock_folder(&staging, Hold::Exclusive, Wait::No) {
                Ok(Some(alive)) => alive,
                Ok(None) | Err(_) => {
                    let _ = fs::remove_dir(&staging);
                    pending.retain(|p| p != &staging);
                    return Err(ReportError::Busy { path: target });
                }
            }
        };
        drop(lock);
        Ok(OutputSet {
            target,
            staging,
            names: names.iter().map(|n| n.to_string()).collect(),
            run_id,
            placement,
            _above: above,
            _alive: alive,
            committed: false,
            created,
        })
    }

    /// Adds the file `name` to the set (a name known only once computed);
    /// returns where to write it.
    ///
    /// # Errors
    /// [`ReportError::Name`] for a name that is not a plain file name.
    pub fn add(&mut self, name: &str) -> Result<PathBuf, ReportError> {
        check_name(name)?;
        if !self.names.iter().any(|n| n == name) {
            self.names.push(name.to_string());
        }
        Ok(self.staging.join(name))
    }

    /// Checks, before any computing, that a run may write the folder `dir`
    /// (see [`OutputSet::write_one`]), as the file system judges it.
    ///
    /// # Errors
    /// [`ReportError::Unwritable`], naming `dir` (and the folder above it
    /// that refuses, when `dir` does not exist yet).
    pub fn check_folder(dir: &Path) -> Result<(), ReportError> {
        check_writable(dir).map_err(unwritable_at(dir))
    }

    /// Writes the one file `name` into the folder `dir` (created if needed)
    /// atomically, under the folder's lock: waits while a set is swapped
    /// into it (or into a folder above it), so that no swap drops the file.
    /// The folder itself is never swapped.
    ///
    /// # Errors
    /// A bad name, a folder that cannot be created or written, or the write
    /// failed.
    pub fn write_one(dir: &Path, name: &str, bytes: &[u8]) -> Result<PathBuf, ReportError> {
        check_name(name)?;
        check_writable(dir).map_err(unwritable_at(dir))?;
        fs::create_dir_all(dir).map_err(unwritable_at(dir))?;
        let target = fs::canonicalize(dir).map_err(unwritable_at(dir))?;
        let _above = lock_ancestors(&target).map_err(unwritable_at(dir))?;
        let _lock = lock_folder(&target, Hold::Shared, Wait::Yes).map_err(unwritable_at(dir))?;
        let path = dir.join(name);
        write_atomic(&path, bytes)?;
        Ok(path)
    }

    /// Where to write the set's file `name` (in the staging folder).
    ///
    /// # Panics
    /// If `name` is not one of the set's names.
    #[track_caller]
    pub fn path(&self, name: &str) -> PathBuf {
        assert!(
            self.names.iter().any(|n| n == name),
            "`{name}` is not a file of this output set"
        );
        self.staging.join(name)
    }

    /// This run's identifier.
    pub fn run_id(&self) -> &str {
        &self.run_id
    }

    /// The target folder.
    pub fn folder(&self) -> &Path {
        &self.target
    }
    /// Seals the files written so far: marks each with the run's identifier
    /// where its format has room for a note readers skip (a comment in SVG
    /// and VTU, a `tEXt` chunk in PNG; CSV has none — a comment line breaks
    /// most CSV readers — and JSON no comments), and returns the run's record
    /// of them: each file's size and FNV-1a hash, so that a folder holding
    /// files of two runs is found out ([`check_manifest`]). One read of each
    /// file; the set's JSON report, written after, carries the record.
    ///
    /// # Errors
    /// A staged file could not be read or rewritten.
    pub fn seal(&self) -> Result<RunRecord, ReportError> {
        let note = format!("ringmesh run {}", self.run_id);
        let mut files = Vec::new();
        for name in &self.names {
            let path = self.staging.join(name);
            if !path.is_file() {
                continue;
            }
            let bytes = fs::read(&path).map_err(at(&path))?;
            let stamped = match path.extension().and_then(|e| e.to_str()) {
                Some("svg" | "vtu") => std::str::from_utf8(&bytes)
                    .ok()
                    .map(|text| xml_with_comment(text, &note).into_bytes()),
                Some("png") => png_with_text(&bytes, "ringmesh-run", &self.run_id),
                _ => None,
            };
            let bytes = match stamped {
                Some(stamped) => {
                    write_atomic(&path, &stamped)?;
                    stamped
                }
                None => bytes,
            };
            files.push(FileRecord {
                name: name.clone(),
                bytes: bytes.len(),
                fnv1a64: format!("{:016x}", fnv1a64(&bytes)),
            });
        }
        Ok(RunRecord {
            id: self.run_id.clone(),
            files,
        })
    }

    /// Publishes the written set into the target folder, keeping every other
    /// entry of the folder; returns the set's paths there.
    ///
    /// # Errors
    /// A file of the set that was not written, a folder in the target that
    /// has become a mount point, or the file system refused (the target
    /// folder is then as it was); after a swap, a folder of the target that
    /// could not be given back (named, with where it is).
    pub fn commit(mut self) -> Result<Vec<PathBuf>, ReportError> {
        for name in &self.names {
            let path = self.staging.join(name);
            if !path.is_file() {
                return Err(ReportError::Io {
                    path,
                    source: io::Error::new(io::ErrorKind::NotFound, "not written"),
                });
            }
        }
        let _lock = lock_folder(&self.target, Hold::Exclusive, Wait::Yes)
            .map_err(at(&self.target))?
            .expect("a waiting lock is always taken");
        match self.placement {
            Placement::Swap => self.swap()?,
            Placement::InPlace => self.rename_each()?,
        }
        Ok(self.names.iter().map(|n| self.target.join(n)).collect())
    }

    /// Publishes by swapping the staging folder with the target (under the
    /// target's lock).
    fn swap(&mut self) -> Result<(), ReportError> {
        check_no_mount_points(&self.target)?;
        let kept = self.give_staging_the_others()?;
        let permissions = fs::metadata(&self.target)
            .map_err(at(&self.target))?
            .permissions();
        fs::set_permissions(&self.staging, permissions).map_err(at(&self.staging))?;
        // Held across the swap and the tidying after it: a signal handler
        // waits for them, and then finds only this run's files to remove.
        let pending = lock_pending();
        exchange(&self.staging, &self.target).map_err(at(&self.target))?;
        self.committed = true;
        // The staging path now holds the previous folder.
        let old = self.staging.clone();
        // A folder that could not be given back leaves the previous folder
        // as it is, named in the error.
        let result = give_back(&old, &self.target, &kept)
            .and_then(|()| empty_old_folder(&old, &self.target, &self.names, &kept));
        drop(pending);
        unregister(&self.staging);
        result
    }

    /// Gives the staging folder every entry of the target that is not a
    /// file of the set: files (and other entries that are not folders) as
    /// hard links (copies where the file system has none), symbolic links
    /// recreated, folders as empty stand-ins with the same permissions.
    /// Returns them.
    fn give_staging_the_others(&self) -> Result<Vec<Kept>, ReportError> {
        let mut kept = Vec::new();
        for entry in fs::read_dir(&self.target).map_err(at(&self.target))? {
            let entry = entry.map_err(at(&self.target))?;
            let name = entry.file_name();
            if self.names.iter().any(|n| name == n.as_str()) {
                continue;
            }
            let from = entry.path();
            let to = self.staging.join(&name);
            let kind = entry.file_type().map_err(at(&from))?;
            if kind.is_dir() {
                fs::create_dir(&to).map_err(at(&to))?;
                if let Ok(m) = fs::metadata(&from) {
                    let _ = fs::set_permissions(&to, m.permissions());
                }
            } else if kind.is_symlink() {
                let link = fs::read_link(&from).map_err(at(&from))?;
                std::os::unix::fs::symlink(link, &to).map_err(at(&to))?;
            } else if fs::hard_link(&from, &to).is_err() {
                fs::copy(&from, &to).map_err(at(&to))?;
            }
            kept.push(Kept {
                name,
                folder: kind.is_dir(),
            });
        }
        Ok(kept)
    }

    /// Publishes by renaming each file into the target, JSON last (under
    /// the target's lock), then removes the staging folder.
    fn rename_each(&mut self) -> Result<(), ReportError> {
        let mut order: Vec<&String> = self.names.iter().collect();
        order.sort_by_key(|n| n.ends_with(".json"));
        // A signal handler waits for the renames: all of them or none.
        let pending = lock_pending();
        for name in order {
            let to = self.target.join(name);
            fs::rename(self.staging.join(name), &to).map_err(at(&to))?;
        }
        self.committed = true;
        let _ = fs::remove_dir_all(&self.staging);
        drop(pending);
        unregister(&self.staging);
        Ok(())
    }
}

impl Drop for OutputSet {
    fn drop(&mut self) {
        if !self.committed {
            // It holds this run's files, hard links and empty stand-ins only.
            let _ = fs::remove_dir_all(&self.staging);
            unregister(&self.staging);
            if self.created {
                // Only if still empty: a file another writer put there stays.
                let _ = fs::remove_dir(&self.target);
            }
        }
    }
}

/// An entry of the target that the staging folder was given before a swap.
#[derive(Debug)]
struct Kept {
    name: OsString,
    folder: bool,
}

/// Refuses a target holding a mount point ([`ReportError::MountPoint`]).
fn check_no_mount_points(target: &Path) -> Result<(), ReportError> {
    let mounts = mount_points_in(target, &device_of).map_err(unwritable_at(target))?;
    if mounts.is_empty() {
        Ok(())
    } else {
        Err(ReportError::MountPoint {
            path: target.to_path_buf(),
            mounts,
        })
    }
}

/// After a swap: gives the new folder `new` back each entry `kept` of the
/// previous one, now in `old`, by exchanging it with its stand-in — the
/// entry itself, as it is now (replaced, or written into, meanwhile). One
/// that its writer removed meanwhile loses its stand-in too.
fn give_back(old: &Path, new: &Path, kept: &[Kept]) -> Result<(), ReportError> {
    let mut failed = None;
    for k in kept {
        let (o, n) = (old.join(&k.name), new.join(&k.name));
        match fs::symlink_metadata(&o) {
            Ok(m) => {
                let same = fs::symlink_metadata(&n)
                    .is_ok_and(|s| (s.dev(), s.ino()) == (m.dev(), m.ino()));
                if !same {
                    if let Err(e) = exchange(&o, &n) {
                        failed.get_or_insert(ReportError::Io {
                            path: n,
                            source: io::Error::new(
                                e.kind(),
                                format!("could not be put back ({e}); it is at {}", o.display()),
                            ),
                        });
                    }
                }
            }
            Err(_) if k.folder => {
                let _ = fs::remove_dir(&n);
            }
            Err(_) => {
                let _ = fs::remove_file(&n);
            }
        }
    }
    failed.map_or(Ok(()), Err)
}

/// After a swap: removes from the previous folder `old` the set's previous
/// files and the stand-ins given back, moves into the new folder `new`
/// whatever a writer that takes no lock put there meanwhile, and removes
/// `old` once it is empty — never an entry the run did not write.
fn empty_old_folder(
    old: &Path,
    new: &Path,
    names: &[String],
    kept: &[Kept],
) -> Result<(), ReportError> {
    for _ in 0..EMPTYING_ROUNDS {
        let entries = fs::read_dir(old).map_err(at(old))?;
        for entry in entries.flatten() {
            let name = entry.file_name();
            let path = entry.path();
            let folder = entry.file_type().is_ok_and(|t| t.is_dir());
            let ours = !folder && names.iter().any(|n| name == n.as_str());
            match kept.iter().find(|k| k.name == name) {
                _ if ours => {
                    let _ = fs::remove_file(&path);
                }
                // The stand-in of a folder: what was written into it
                // between the swap and the giving back goes to the folder.
                Some(k) if k.folder && folder => {
                    move_entries(&path, &new.join(&name));
                    let _ = fs::remove_dir(&path);
                }
                Some(_) if !folder => {
                    let _ = fs::remove_file(&path);
                }
                _ => move_into(&path, &new.join(&name)),
            }
        }
        match fs::remove_dir(old) {
            Ok(()) => return Ok(()),
            Err(e) if e.kind() == io::ErrorKind::NotFound => return Ok(()),
            Err(_) => continue,
        }
    }
    Err(ReportError::Io {
        path: old.to_path_buf(),
        source: io::Error::new(
            io::ErrorKind::DirectoryNotEmpty,
            "another program keeps writing into the previous folder; it is left as it is",
        ),
    })
}

/// Moves the entry `from` to `to` unless `to` exists: then a folder's
/// entries are moved into it one by one, and of two files the one at `to`,
/// written later into the live folder, stays. An entry that cannot be
/// moved for any other reason stays where it is.
fn move_into(from: &Path, to: &Path) {
    match rename_noreplace(from, to) {
        Err(e) if e.kind() == io::ErrorKind::AlreadyExists => {
            let folder = |p: &Path| fs::symlink_metadata(p).is_ok_and(|m| m.is_dir());
            if folder(from) && folder(to) {
                move_entries(from, to);
                let _ = fs::remove_dir(from);
            } else if !folder(from) {
                let _ = fs::remove_file(from);
            }
        }
        Ok(()) | Err(_) => {}
    }
}

/// Moves every entry of the folder `from` into the folder `to` ([`move_into`]).
fn move_entries(from: &Path, to: &Path) {
    if let Ok(entries) = fs::read_dir(from) {
        for entry in entries.flatten() {
            move_into(&entry.path(), &to.join(entry.file_name()));
        }
    }
}

/// What a killed run left beside the target `target` (its staging folder,
/// or the previous folder of a swap it did not finish tidying): each folder
/// in it that is not an empty stand-in goes back to the target (exchanged
/// with its stand-in there, or moved), the rest is removed.
fn remove_left_staging(left: &Path, target: &Path) {
    if let Ok(entries) = fs::read_dir(left) {
        for entry in entries.flatten() {
            let path = entry.path();
            let to = target.join(entry.file_name());
            let folder = entry.file_type().is_ok_and(|t| t.is_dir());
            let empty = |p: &Path| fs::read_dir(p).is_ok_and(|mut d| d.next().is_none());
            if folder && !empty(&path) {
                if to.is_dir() && !to.is_symlink() && empty(&to) {
                    let _ = exchange(&path, &to);
                } else {
                    move_into(&path, &to);
                }
            }
        }
    }
    let _ = fs::remove_dir_all(left);
}

/// A run's identifier and the files it wrote (`design.json`'s `run`).
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct RunRecord {
    /// The run's identifier.
    pub id: String,
    /// The other files of the set as the run wrote them.
    pub files: Vec<FileRecord>,
}

/// One file of a run.
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct FileRecord {
    /// Its name in the folder.
    pub name: String,
    /// Its size, bytes.
    pub bytes: usize,
    /// Its 64-bit FNV-1a hash, hexadecimal.
    pub fnv1a64: String,
}

/// Checks that the files of `record` in `dir` are those the run wrote.
///
/// # Errors
/// The first file that is missing ([`ReportError::ManifestUnreadable`]) or
/// differs ([`ReportError::MixedRuns`]), named.
pub fn check_manifest(dir: &Path, record: &RunRecord) -> Result<(), ReportError> {
    for file in &record.files {
        let bytes =
            fs::read(dir.join(&file.name)).map_err(|source| ReportError::ManifestUnreadable {
                file: file.name.clone(),
                run: record.id.clone(),
                source,
            })?;
        if bytes.len() != file.bytes || format!("{:016x}", fnv1a64(&bytes)) != file.fnv1a64 {
            return Err(ReportError::MixedRuns {
                file: file.name.clone(),
                run: record.id.clone(),
            });
        }
    }
    Ok(())
}

/// 64-bit FNV-1a.
fn fnv1a64(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| {
        (h ^ u64::from(b)).wrapping_mul(0x0000_0100_0000_01b3)
    })
}

/// `text` (XML) with the comment `note` after its declaration, or first.
fn xml_with_comment(text: &str, note: &str) -> String {
    let comment = format!("<!-- {note} -->\n");
    let at = if text.starts_with("<?xml") {
        text.find("?>").map_or(0, |i| {
            let end = i + 2;
            end + usize::from(text[end..].starts_with('\n'))
        })
    } else {
        0
    };
    format!("{}{comment}{}", &text[..at], &text[at..])
}

/// The PNG `png` with a `tEXt` chunk `keyword`/`text` after its `IHDR`
/// chunk; `None` if `png` does not start with a signature and `IHDR`.
fn png_with_text(png: &[u8], keyword: &str, text: &str) -> Option<Vec<u8>> {
    const SIGNATURE: &[u8] = b"\x89PNG\r\n\x1a\n";
    if !png.starts_with(SIGNATURE) || png.get(12..16) != Some(b"IHDR") {
        return None;
    }
    let length = u32::from_be_bytes(png.get(8..12)?.try_into().ok()?) as usize;
    let end = 8 + 12 + length;
    if png.len() < end {
        return None;
    }
    let mut body = b"tEXt".to_vec();
    body.extend_from_slice(keyword.as_bytes());
    body.push(0);
    body.extend_from_slice(text.as_bytes());
    let mut out = png[..end].to_vec();
    out.extend_from_slice(&((body.len() - 4) as u32).to_be_bytes());
    out.extend_from_slice(&body);
    out.extend_from_slice(&crc32(&body).to_be_bytes());
    out.extend_from_slice(&png[end..]);
    Some(out)
}

/// The CRC-32 of PNG chunks (ISO 3309), bit by bit: a few dozen bytes here.
fn crc32(bytes: &[u8]) -> u32 {
    let mut crc = u32::MAX;
    for &b in bytes {
        crc ^= u32::from(b);
        for _ in 0..8 {
            crc = if crc & 1 == 1 {
                (crc >> 1) ^ 0xedb8_8320
            } else {
                crc >> 1
            };
        }
    }
    !crc
}

/// The [`ReportError::Io`] of a file system call on `path`.
fn at(path: &Path) -> impl FnOnce(io::Error) -> ReportError {
    let path = path.to_path_buf();
    move |source| ReportError::Io { path, source }
}

/// The [`ReportError::Unwritable`] of a call that prepares the folder `path`.
fn unwritable_at(path: &Path) -> impl FnOnce(io::Error) -> ReportError {
    let path = path.to_path_buf();
    move |source| ReportError::Unwritable { path, source }
}

/// A plain file name: not empty, no separator, not `.`/`..`, not hidden,
/// at most [`NAME_MAX`] bytes.
fn check_name(name: &str) -> Result<(), ReportError> {
    let reason = if name.is_empty() {
        Some("it is empty")
    } else if name.contains(['/', '\\', '\0']) {
        Some("it contains a path separator")
    } else if name.starts_with('.') {
        Some("it starts with a dot")
    } else if name.len() > NAME_MAX {
        Some("it is longer than 255 bytes")
    } else {
        None
    };
    match reason {
        Some(reason) => Err(ReportError::Name {
            name: name.chars().take(80).collect(),
            reason,
        }),
        None => Ok(()),
    }
}

/// Swaps the entries `a` and `b` in one step.
#[cfg(target_os = "linux")]
fn exchange(a: &Path, b: &Path) -> io::Result<()> {
    use rustix::fs::{renameat_with, RenameFlags, CWD};
    renameat_with(CWD, a, CWD, b, RenameFlags::EXCHANGE).map_err(io::Error::from)
}

/// Swaps the entries `a` and `b`: without `RENAME_EXCHANGE`, two renames
/// (a reader between them finds no entry, never a mix).
#[cfg(not(target_os = "linux"))]
fn exchange(a: &Path, b: &Path) -> io::Result<()> {
    let aside = a.with_extension("previous");
    fs::rename(b, &aside)?;
    fs::rename(a, b)?;
    fs::rename(&aside, a)
}

/// Renames `from` to `to`, failing if `to` exists.
#[cfg(target_os = "linux")]
fn rename_noreplace(from: &Path, to: &Path) -> io::Result<()> {
    use rustix::fs::{renameat_with, RenameFlags, CWD};
    renameat_with(CWD, from, CWD, to, RenameFlags::NOREPLACE).map_err(io::Error::from)
}

/// Renames `from` to `to`, failing if `to` exists (checked first).
#[cfg(not(target_os = "linux"))]
fn rename_noreplace(from: &Path, to: &Path) -> io::Result<()> {
    if fs::symlink_metadata(to).is_ok() {
        return Err(io::ErrorKind::AlreadyExists.into());
    }
    fs::rename(from, to)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn listing(dir: &Path) -> Vec<String> {
        let mut names: Vec<String> = fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        names
    }

    #[test]
    fn a_set_replaces_its_files_keeps_the_others_and_leaves_nothing_beside() {
        let root = tempfile::tempdir().unwrap();
        let dir = root.path().join("out");
        fs::create_dir_all(dir.join("sub")).unwrap();
        fs::write(dir.join("a.csv"), "old").unwrap();
        fs::write(dir.join("other.txt"), "kept").unwrap();
        fs::write(dir.join("sub/deep.txt"), "kept too").unwrap();
        let set = OutputSet::begin(&dir, &["a.csv", "b.json"]).unwrap();
        fs::write(set.path("a.csv"), "new").unwrap();
        // Nothing of the new set is visible before the commit.
        assert_eq!(fs::read_to_string(dir.join("a.csv")).unwrap(), "old");
        fs::write(set.path("b.json"), "{}").unwrap();
        let written = set.commit().unwrap();
        assert_eq!(written.len(), 2);
        assert_eq!(listing(&dir), ["a.csv", "b.json", "other.txt", "sub"]);
        assert_eq!(fs::read_to_string(dir.join("a.csv")).unwrap(), "new");
        assert_eq!(fs::read_to_string(dir.join("other.txt")).unwrap(), "kept");
        assert_eq!(
            fs::read_to_string(dir.join("sub/deep.txt")).unwrap(),
            "kept too"
        );
        assert_eq!(listing(root.path()), ["out"]);
    }

    #[test]
    fn an_unfinished_set_changes_nothing_and_a_second_run_is_refused() {
        let root = tempfile::tempdir().unwrap();
        let dir = root.path().join("out");
        let set = OutputSet::begin(&dir, &["a.csv"]).unwrap();
        fs::write(set.path("a.csv"), "new").unwrap();
        let second = OutputSet::begin(&dir, &["a.csv"]);
        assert!(
            matches!(second, Err(ReportError::Busy { .. })),
            "{second:?}"
        );
        drop(set);
        // The folder this run created goes with it, being empty.
        assert!(!dir.exists());
        assert!(listing(root.path()).is_empty());
        // The lock went with the set.
        OutputSet::begin(&dir, &["a.csv"]).unwrap();
    }

    #[test]
    fn stamps_keep_their_formats_and_the_manifest_finds_a_mixed_folder() {
        // CRC-32 check value of the standard.
        assert_eq!(crc32(b"123456789"), 0xcbf4_3926);
        let vtu = "<?xml version=\"1.0\"?>\n<VTKFile/>\n";
        assert_eq!(
            xml_with_comment(vtu, "ringmesh run 1"),
            "<?xml version=\"1.0\"?>\n<!-- ringmesh run 1 -->\n<VTKFile/>\n"
        );
        assert_eq!(xml_with_comment("<svg/>", "r"), "<!-- r -->\n<svg/>");
        let ihdr_end = 8 + 12 + 13;
        let mut png = b"\x89PNG\r\n\x1a\n\0\0\0\x0dIHDR".to_vec();
        png.resize(ihdr_end, 0);
        png.extend_from_slice(b"rest");
        let stamped = png_with_text(&png, "k", "v").unwrap();
        assert_eq!(&stamped[ihdr_end + 4..ihdr_end + 8], b"tEXt");
        assert_eq!(&stamped[ihdr_end + 8..ihdr_end + 11], b"k\0v");
        assert!(stamped.ends_with(b"rest"));
        assert!(png_with_text(b"not a png", "k", "v").is_none());

        let root = tempfile::tempdir().unwrap();
        let dir = root.path().join("out");
        let set = OutputSet::begin(&dir, &["a.csv", "b.svg"]).unwrap();
        fs::write(set.path("a.csv"), "x,y\n").unwrap();
        fs::write(set.path("b.svg"), "<svg/>").unwrap();
        let record = set.seal().unwrap();
        set.commit().unwrap();
        let svg = fs::read_to_string(dir.join("b.svg")).unwrap();
        assert!(svg.contains(&record.id), "{svg}");
        check_manifest(&dir, &record).unwrap();
        fs::write(dir.join("a.csv"), "x,y\n1,2\n").unwrap();
        let mixed = check_manifest(&dir, &record).unwrap_err();
        assert!(
            matches!(&mixed, ReportError::MixedRuns { file, .. } if file == "a.csv"),
            "{mixed}"
        );
        assert!(mixed.to_string().contains("a.csv"), "{mixed}");
    }

    #[test]
    fn bad_names_are_refused_before_anything_is_created() {
        let root = tempfile::tempdir().unwrap();
        let dir = root.path().join("out");
        for name in ["", "a/b", ".hidden", &"x".repeat(300)] {
            let e = OutputSet::begin(&dir, &[name]).unwrap_err();
            assert!(matches!(e, ReportError::Name { .. }), "{e}");
        }
        assert!(!dir.exists());
    }

    /// Every entry of `dir` and the folders below it, as relative paths.
    fn tree(dir: &Path) -> Vec<String> {
        let mut all = Vec::new();
        let mut stack = vec![dir.to_path_buf()];
        while let Some(d) = stack.pop() {
            for e in fs::read_dir(&d).unwrap().flatten() {
                let p = e.path();
                all.push(p.strip_prefix(dir).unwrap().to_string_lossy().into_owned());
                if e.file_type().unwrap().is_dir() {
                    stack.push(p);
                }
            }
        }
        all.sort();
        all
    }

    /// One set of `a.csv` and `b.json` holding `text`, swapped into `dir`.
    fn one_set(dir: &Path, text: &str) -> Result<Vec<PathBuf>, ReportError> {
        let set = OutputSet::begin(dir, &["a.csv", "b.json"])?;
        fs::write(set.path("a.csv"), text).unwrap();
        fs::write(set.path("b.json"), text).unwrap();
        set.commit()
    }

    /// Issue 40 item 3: while sets are swapped into `X` again and again, a
    /// program that takes no lock writes plain files into `X` and into a
    /// folder in it, and ringmesh single-file writers (`fdm -o X/f.json`)
    /// write theirs: every file either reported written is there afterwards
    /// with its content, the folder holds the last set, and nothing is
    /// left beside it or in it (no staging folder, no temporary file).
    #[test]
    fn files_written_during_repeated_swaps_are_all_kept() {
        use std::sync::atomic::{AtomicUsize, Ordering};
        let root = tempfile::tempdir().unwrap();
        let dir = root.path().join("X");
        fs::create_dir_all(dir.join("sub")).unwrap();
        one_set(&dir, "first").unwrap();
        let swaps = AtomicUsize::new(0);
        // Each writer keeps pace with the swaps (no more than a few writes
        // ahead of them), so that its writes are spread over all of them.
        let pace = |per_swap: usize, i: usize| {
            while swaps.load(Ordering::SeqCst) < i / per_swap {
                std::thread::yield_now();
            }
        };
        const FOREIGN: usize = 540;
        const OURS: usize = 100;
        let (foreign, during, failed, ours) = std::thread::scope(|scope| {
            let foreign = scope.spawn(|| {
                let (mut written, mut during, mut failed) = (Vec::new(), 0, Vec::new());
                for i in 0..FOREIGN {
                    pace(5, i);
                    let path = if i % 3 == 0 {
                        dir.join("sub").join(format!("g-{i}.txt"))
                    } else {
                        dir.join(format!("f-{i}.txt"))
                    };
                    let before = swaps.load(Ordering::SeqCst);
                    match fs::write(&path, format!("foreign {i}")) {
                        Ok(()) => written.push((path, format!("foreign {i}"))),
                        Err(e) => failed.push(format!("{}: {e}", path.display())),
                    }
                    // A swap finished while the file was written.
                    during += usize::from(swaps.load(Ordering::SeqCst) != before);
                }
                (written, during, failed)
            });
            let ringmesh = scope.spawn(|| {
                (0..OURS)
                    .map(|i| {
                        pace(1, i);
                        let name = format!("fdm-{i}.json");
                        let path = OutputSet::write_one(&dir, &name, name.as_bytes()).unwrap();
                        (path, name)
                    })
                    .collect::<Vec<_>>()
            });
            let mut round = 0;
            while !(foreign.is_finished() && ringmesh.is_finished()) {
                one_set(&dir, &format!("set {round}")).unwrap();
                swaps.fetch_add(1, Ordering::SeqCst);
                round += 1;
            }
            let (written, during, failed) = foreign.join().unwrap();
            (written, during, failed, ringmesh.join().unwrap())
        });
        let swaps = swaps.into_inner();
        let lost: Vec<_> = foreign
            .iter()
            .chain(&ours)
            .filter(|(path, text)| fs::read_to_string(path).ok().as_deref() != Some(text))
            .map(|(path, _)| path.display().to_string())
            .collect();
        eprintln!(
            "{swaps} swaps; {} foreign writes ({during} met the end of a swap, {} refused to \
             the writer: {failed:?}), {} ringmesh writes; {} lost",
            foreign.len(),
            failed.len(),
            ours.len(),
            lost.len()
        );
        // A write whose path was looked up in the previous folder and which
        // creates its file after that folder is gone fails, and its writer
        // is told (ENOENT); it is not lost.
        assert!(foreign.len() >= 500, "{failed:?}");
        assert!(swaps >= FOREIGN / 5, "{swaps} swaps");
        assert!(lost.is_empty(), "lost: {lost:?}");
        let last = format!("set {}", swaps - 1);
        assert_eq!(fs::read_to_string(dir.join("a.csv")).unwrap(), last);
        assert_eq!(listing(root.path()), ["X"]);
        let left: Vec<_> = tree(&dir)
            .into_iter()
            .filter(|n| n.contains(".staging-") || n.ends_with(".tmp"))
            .collect();
        assert!(left.is_empty(), "{left:?}");
        assert_eq!(tree(&dir).len(), 3 + foreign.len() + OURS);
    }

    /// Issue 40 item 3: sets swapped into `X` and into `X/sub` at the same
    /// time (two runs, each again and again) all succeed, and each folder
    /// holds its last set: the run into `X` never takes `X/sub`'s files,
    /// nor the other way round; no staging folder is left.
    #[test]
    fn sets_into_a_folder_and_a_folder_in_it_never_take_each_others_files() {
        let root = tempfile::tempdir().unwrap();
        let dir = root.path().join("X");
        let sub = dir.join("sub");
        const ROUNDS: usize = 40;
        std::thread::scope(|scope| {
            let outer = scope.spawn(|| {
                for i in 0..ROUNDS {
                    one_set(&dir, &format!("outer {i}")).unwrap();
                    std::thread::yield_now();
                }
            });
            let inner = scope.spawn(|| {
                for i in 0..ROUNDS {
                    let set = OutputSet::begin(&sub, &["s.csv"]).unwrap();
                    fs::write(set.path("s.csv"), format!("inner {i}")).unwrap();
                    let written = set.commit().unwrap();
                    // What the run reports written is there — for a reader
                    // that takes `X`'s lock, as every ringmesh writer does:
                    // a swap of `X` moves `X/sub` into the new `X` under it,
                    // so an unlocked read can fall in between.
                    let _reading = lock_folder(&dir, Hold::Shared, Wait::Yes).unwrap();
                    assert_eq!(
                        fs::read_to_string(&written[0]).unwrap(),
                        format!("inner {i}")
                    );
                    std::thread::yield_now();
                }
            });
            outer.join().unwrap();
            inner.join().unwrap();
        });
        let last = ROUNDS - 1;
        assert_eq!(
            fs::read_to_string(dir.join("a.csv")).unwrap(),
            format!("outer {last}")
        );
        assert_eq!(
            fs::read_to_string(sub.join("s.csv")).unwrap(),
            format!("inner {last}")
        );
        assert_eq!(
            tree(root.path()),
            ["X", "X/a.csv", "X/b.json", "X/sub", "X/sub/s.csv"]
        );
    }

    /// A swap gives the folders of the target back themselves, not copies:
    /// a file kept open in one and written after the swap is there, and the
    /// folder is the same folder (what is mounted below it, or a shell's
    /// working folder in it, stays).
    #[test]
    fn a_swap_gives_back_the_folders_themselves() {
        use std::io::Write as _;
        let root = tempfile::tempdir().unwrap();
        let dir = root.path().join("X");
        fs::create_dir_all(dir.join("sub/deeper")).unwrap();
        let before = fs::metadata(dir.join("sub")).unwrap().ino();
        let mut open = File::create(dir.join("sub/deeper/log.txt")).unwrap();
        one_set(&dir, "one").unwrap();
        open.write_all(b"written after the swap").unwrap();
        drop(open);
        assert_eq!(fs::metadata(dir.join("sub")).unwrap().ino(), before);
        assert_eq!(
            fs::read_to_string(dir.join("sub/deeper/log.txt")).unwrap(),
            "written after the swap"
        );
        assert_eq!(listing(root.path()), ["X"]);
    }

    /// What a run killed during its swap left beside the folder — the
    /// previous folder, holding a folder of the target whose stand-in is in
    /// the target — is given back by the next set, never removed with it.
    #[test]
    fn the_next_set_gives_back_what_a_killed_swap_left() {
        let root = tempfile::tempdir().unwrap();
        let dir = root.path().join("X");
        fs::create_dir_all(dir.join("sub")).unwrap();
        let left = root.path().join(".X.staging-1-2-3");
        fs::create_dir_all(left.join("sub")).unwrap();
        fs::write(left.join("sub/precious.txt"), "kept").unwrap();
        fs::write(left.join("a.csv"), "the previous set's").unwrap();
        one_set(&dir, "next").unwrap();
        assert_eq!(
            fs::read_to_string(dir.join("sub/precious.txt")).unwrap(),
            "kept"
        );
        assert_eq!(fs::read_to_string(dir.join("a.csv")).unwrap(), "next");
        assert_eq!(listing(root.path()), ["X"]);
    }

    /// Files written beside an output file are renamed into its folder, the
    /// folder itself never swapped; a second set into the folder meanwhile
    /// is refused.
    #[test]
    fn a_set_beside_a_file_leaves_its_folder_in_place() {
        let root = tempfile::tempdir().unwrap();
        let dir = root.path().join("D");
        fs::create_dir_all(&dir).unwrap();
        fs::write(dir.join("notes.txt"), "mine").unwrap();
        let inode = fs::metadata(&dir).unwrap().ino();
        let set = OutputSet::begin_beside(&dir, &["x.json", "x-path.csv"]).unwrap();
        assert!(matches!(
            OutputSet::begin(&dir, &["y.csv"]),
            Err(ReportError::Busy { .. })
        ));
        fs::write(set.path("x.json"), "{}").unwrap();
        fs::write(set.path("x-path.csv"), "a\n").unwrap();
        let written = set.commit().unwrap();
        assert_eq!(
            written,
            [
                dir.canonicalize().unwrap().join("x.json"),
                dir.canonicalize().unwrap().join("x-path.csv")
            ]
        );
        assert_eq!(fs::metadata(&dir).unwrap().ino(), inode);
        assert_eq!(listing(&dir), ["notes.txt", "x-path.csv", "x.json"]);
        assert_eq!(listing(root.path()), ["D"]);
    }
}
