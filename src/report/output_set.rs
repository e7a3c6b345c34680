//! A command's output files as one set: all of them or none.
//!
//! [`OutputSet::begin`] runs before any computing: it creates the target
//! folder, takes its lock (a second run into the same folder is refused,
//! naming it), and creates a staging folder beside it — which proves the
//! place writable and the names valid. The command writes its files into the
//! staging folder; [`OutputSet::commit`] then gives the staging folder every
//! other entry of the target (hard links: the files other commands wrote
//! there stay) and swaps the two folders with one atomic `renameat2`
//! `RENAME_EXCHANGE`. A reader, or a run killed at any moment, sees the
//! previous complete set or the new complete set, never a mix.
//!
//! What is left behind by a run killed with SIGKILL is a staging folder
//! beside the target (`.NAME.staging-RUN`), never a file in it; the next
//! run into the same folder removes it. SIGINT and SIGTERM remove it at once
//! ([`super::abandon_all_and_exit`], which the CLI's signal handler calls), with every
//! temporary file [`super::write_atomic`] has open (`pending.rs`).
//!
//! The lock is an advisory `flock` on the target folder itself, so it leaves
//! no file behind; a run that locked a folder which another run has just
//! swapped away checks the inode and locks the new one.

use std::fs::{self, File};
use std::io;
use std::path::{Path, PathBuf};
use std::time::{SystemTime, UNIX_EPOCH};

use rustix::fs::FlockOperation;
use serde::Serialize;

use super::atomic::write_atomic;
use super::error::ReportError;
use super::pending::{lock_pending, unregister};

/// Longest file name most file systems take, bytes.
const NAME_MAX: usize = 255;

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

/// The files of one run of one command, written into a staging folder and
/// swapped into the target folder as one.
#[derive(Debug)]
pub struct OutputSet {
    target: PathBuf,
    staging: PathBuf,
    names: Vec<String>,
    run_id: String,
    /// Holds the target folder's lock while the set lives.
    _lock: File,
    committed: bool,
    /// Whether this run created the target folder: a refusal after `begin`
    /// then leaves no empty folder behind.
    created: bool,
}

impl OutputSet {
    /// Prepares a set of the files `names` in the folder `dir` (created if
    /// needed): checks the names, locks the folder, removes what killed runs
    /// left beside it, and creates the staging folder.
    ///
    /// # Errors
    /// [`ReportError::Name`] for a name that is not a plain file name,
    /// [`ReportError::Busy`] when another run holds the folder,
    /// [`ReportError::Unwritable`] when the folder or the staging folder
    /// beside it cannot be created.
    pub fn begin(dir: &Path, names: &[&str]) -> Result<OutputSet, ReportError> {
        for name in names {
            check_name(name)?;
        }
        let created = fs::symlink_metadata(dir).is_err();
        fs::create_dir_all(dir).map_err(unwritable_at(dir))?;
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
        let lock = lock_folder(&target, Wait::No)?;
        let prefix = format!(".{}.staging-", folder.to_string_lossy());
        if let Ok(entries) = fs::read_dir(parent) {
            for entry in entries.flatten() {
                if entry.file_name().to_string_lossy().starts_with(&prefix) {
                    let _ = fs::remove_dir_all(entry.path());
                }
            }
        }
        let run_id = new_run_id();
        let staging = parent.join(format!("{prefix}{run_id}"));
        // Registered and created under the registry's lock, as in
        // `create_registered`.
        {
            let mut pending = lock_pending();
            if let Err(e) = fs::create_dir(&staging) {
                return Err(unwritable_at(&staging)(e));
            }
            pending.push(staging.clone());
        }
        Ok(OutputSet {
            target,
            staging,
            names: names.iter().map(|n| n.to_string()).collect(),
            run_id,
            _lock: lock,
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

    /// Writes the one file `name` into the folder `dir` (created if needed)
    /// atomically, under the folder's lock: waits while another run holds
    /// it, so that no set swapped in meanwhile drops the file (the shards
    /// of one study, run in parallel, each write one).
    ///
    /// # Errors
    /// A bad name, a folder that cannot be created, or the write failed.
    pub fn write_one(dir: &Path, name: &str, bytes: &[u8]) -> Result<PathBuf, ReportError> {
        check_name(name)?;
        fs::create_dir_all(dir).map_err(unwritable_at(dir))?;
        let _lock = lock_folder(dir, Wait::Yes)?;
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

    /// Swaps the written set into the target folder, keeping every other
    /// entry of the folder; returns the set's paths there.
    ///
    /// # Errors
    /// A file of the set that was not written, or the file system refused
    /// (the target folder is then as it was).
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
        for entry in fs::read_dir(&self.target).map_err(at(&self.target))? {
            let entry = entry.map_err(at(&self.target))?;
            let name = entry.file_name();
            if self.names.iter().any(|n| name == n.as_str()) {
                continue;
            }
            link_tree(&entry.path(), &self.staging.join(&name))?;
        }
        let permissions = fs::metadata(&self.target)
            .map_err(at(&self.target))?
            .permissions();
        fs::set_permissions(&self.staging, permissions).map_err(at(&self.staging))?;
        // Held across the swap: a signal handler waits for it to finish.
        let pending = lock_pending();
        exchange(&self.staging, &self.target).map_err(at(&self.target))?;
        self.committed = true;
        drop(pending);
        // The staging path now holds the previous set.
        let _ = fs::remove_dir_all(&self.staging);
        unregister(&self.staging);
        Ok(self.names.iter().map(|n| self.target.join(n)).collect())
    }
}

impl Drop for OutputSet {
    fn drop(&mut self) {
        if !self.committed {
            let _ = fs::remove_dir_all(&self.staging);
            unregister(&self.staging);
            if self.created {
                // Only if still empty: a file another writer put there stays.
                let _ = fs::remove_dir(&self.target);
            }
        }
    }
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

/// Whether [`lock_folder`] waits for a run that holds the lock.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Wait {
    Yes,
    No,
}

/// Takes the advisory lock of the folder `target` — waiting for another
/// run that holds it, or refusing ([`ReportError::Busy`]) — and retries when
/// the folder was swapped away meanwhile.
fn lock_folder(target: &Path, wait: Wait) -> Result<File, ReportError> {
    use std::os::unix::fs::MetadataExt;
    let io = |e: io::Error| unwritable_at(target)(e);
    let operation = match wait {
        Wait::Yes => FlockOperation::LockExclusive,
        Wait::No => FlockOperation::NonBlockingLockExclusive,
    };
    loop {
        let folder = File::open(target).map_err(io)?;
        match rustix::fs::flock(&folder, operation) {
            Ok(()) => {}
            Err(rustix::io::Errno::WOULDBLOCK) => {
                return Err(ReportError::Busy {
                    path: target.to_path_buf(),
                })
            }
            Err(e) => return Err(io(e.into())),
        }
        let held = folder.metadata().map_err(io)?;
        let now = fs::metadata(target).map_err(io)?;
        if (held.dev(), held.ino()) == (now.dev(), now.ino()) {
            return Ok(folder);
        }
    }
}

/// Hard-links the file or folder tree `from` to `to` (copies where the file
/// system has no hard links); symbolic links are recreated.
fn link_tree(from: &Path, to: &Path) -> Result<(), ReportError> {
    let kind = fs::symlink_metadata(from).map_err(at(from))?.file_type();
    if kind.is_symlink() {
        let link = fs::read_link(from).map_err(at(from))?;
        std::os::unix::fs::symlink(link, to).map_err(at(to))?;
    } else if kind.is_dir() {
        fs::create_dir(to).map_err(at(to))?;
        for entry in fs::read_dir(from).map_err(at(from))? {
            let entry = entry.map_err(at(from))?;
            link_tree(&entry.path(), &to.join(entry.file_name()))?;
        }
    } else if fs::hard_link(from, to).is_err() {
        fs::copy(from, to).map_err(at(to))?;
    }
    Ok(())
}

/// Swaps the folders `a` and `b` in one step.
#[cfg(target_os = "linux")]
fn exchange(a: &Path, b: &Path) -> io::Result<()> {
    use rustix::fs::{renameat_with, RenameFlags, CWD};
    renameat_with(CWD, a, CWD, b, RenameFlags::EXCHANGE).map_err(io::Error::from)
}

/// Swaps the folders `a` and `b`: without `RENAME_EXCHANGE`, two renames
/// (a reader between them finds no folder, never a mix).
#[cfg(not(target_os = "linux"))]
fn exchange(a: &Path, b: &Path) -> io::Result<()> {
    let aside = a.with_extension("previous");
    fs::rename(b, &aside)?;
    fs::rename(a, b)?;
    fs::rename(&aside, a)
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
}
