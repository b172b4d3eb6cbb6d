//! Atomic file output: write to a temporary file beside the target, then
//! rename, so a failed or interrupted write never leaves a half-written file.
//!
//! [`AtomicFile`] is the streaming form (a writer that can also seek, for
//! formats with a summary at the end such as MCAP); [`write_atomic`] and
//! [`write_atomic_with`] are built on it.

use crate::IoError;
use std::fs::File;
use std::io::{BufWriter, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};
use std::sync::Mutex;

/// The temporary files of every [`AtomicFile`] not yet committed or
/// dropped, and of every compressed ROS 2 bag file being read, for
/// [`remove_temporary_files`].
static TEMPORARY: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

pub(crate) fn register(tmp: &Path) {
    if let Ok(mut t) = TEMPORARY.lock() {
        t.push(tmp.to_path_buf());
    }
}

pub(crate) fn unregister(tmp: &Path) {
    if let Ok(mut t) = TEMPORARY.lock() {
        t.retain(|p| p != tmp);
    }
}

/// Removes the temporary file of every [`AtomicFile`] still being written.
/// For a signal handler (SIGINT, SIGTERM) that ends the process, which runs
/// no destructor: without it an interrupted write leaves its `.tmp` file.
pub fn remove_temporary_files() {
    if let Ok(t) = TEMPORARY.lock() {
        for p in t.iter() {
            let _ = std::fs::remove_file(p);
        }
    }
}

/// A file being written atomically: every byte goes to a temporary file in
/// the target's folder, and [`AtomicFile::commit`] flushes, syncs and renames
/// it over the target. Dropped without a commit (an error, a panic, an early
/// return), it removes the temporary file and leaves the target untouched.
///
/// Edge cases: the target's folder must exist and be writable (the error
/// names the target). A target that is a directory is refused. A symbolic
/// link is followed: the file it points to is replaced, not the link. A
/// device or FIFO (`/dev/stdout`, `/dev/null`, a named pipe) is written
/// directly, never replaced by a regular file.
#[derive(Debug)]
pub struct AtomicFile {
    target: PathBuf,
    /// The temporary file renamed over the target; `None` when the target
    /// is a device or FIFO written directly.
    tmp: Option<PathBuf>,
    writer: Option<BufWriter<File>>,
}

impl AtomicFile {
    /// Creates the temporary file for `target` (`.NAME.PID.tmp` beside it),
    /// or opens a device or FIFO target for writing.
    pub fn create(target: &Path) -> Result<Self, IoError> {
        let shown = target;
        let resolved;
        let target = match std::fs::metadata(target) {
            Ok(m) if m.is_dir() => {
                return Err(IoError::io(
                    shown,
                    std::io::Error::new(
                        std::io::ErrorKind::IsADirectory,
                        "is a directory, not a file to write",
                    ),
                ));
            }
            Ok(m) if !m.is_file() => {
                // A device, FIFO or socket: written in place.
                let file = std::fs::OpenOptions::new()
                    .write(true)
                    .open(target)
                    .map_err(|e| IoError::io(shown, e))?;
                return Ok(AtomicFile {
                    target: target.to_path_buf(),
                    tmp: None,
                    writer: Some(BufWriter::with_capacity(1 << 16, file)),
                });
            }
            Ok(_) if target.is_symlink() => {
                // Replace the file the link points to, and keep the link.
                resolved = std::fs::canonicalize(target).map_err(|e| IoError::io(shown, e))?;
                resolved.as_path()
            }
            _ => target,
        };
        let dir = match target.parent() {
            Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
            _ => PathBuf::from("."),
        };
        let name = target.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
        let tmp = dir.join(format!(".{name}.{}.tmp", std::process::id()));
        let file = File::create(&tmp).map_err(|e| IoError::io(shown, e))?;
        register(&tmp);
        Ok(AtomicFile {
            target: target.to_path_buf(),
            tmp: Some(tmp),
            writer: Some(BufWriter::with_capacity(1 << 16, file)),
        })
    }

    /// The path the file will have once committed.
    pub fn target(&self) -> &Path {
        &self.target
    }

    /// Flushes, syncs and renames the temporary file over the target. On an
    /// error the temporary file is removed.
    pub fn commit(mut self) -> Result<(), IoError> {
        let result = (|| {
            let writer =
                self.writer.take().ok_or_else(|| std::io::Error::other("already closed"))?;
            let file = writer.into_inner().map_err(|e| e.into_error())?;
            match &self.tmp {
                Some(tmp) => {
                    file.sync_all()?;
                    std::fs::rename(tmp, &self.target)
                }
                None => Ok(()),
            }
        })();
        result.map_err(|e| IoError::io(&self.target, e))
        // Drop removes the temporary file if the rename did not happen.
    }

    /// Flushes and syncs what was written so far, so that a full disk shows
    /// here rather than at [`AtomicFile::commit`].
    pub fn sync(&mut self) -> Result<(), IoError> {
        let result = self.writer().and_then(|w| {
            w.flush()?;
            w.get_ref().sync_all()
        });
        result.map_err(|e| IoError::io(&self.target, e))
    }

    fn writer(&mut self) -> std::io::Result<&mut BufWriter<File>> {
        self.writer.as_mut().ok_or_else(|| std::io::Error::other("already closed"))
    }
}

impl Write for AtomicFile {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        self.writer()?.write(buf)
    }

    fn write_all(&mut self, buf: &[u8]) -> std::io::Result<()> {
        self.writer()?.write_all(buf)
    }

    fn flush(&mut self) -> std::io::Result<()> {
        self.writer()?.flush()
    }
}

impl Seek for AtomicFile {
    fn seek(&mut self, pos: SeekFrom) -> std::io::Result<u64> {
        self.writer()?.seek(pos)
    }
}

impl Drop for AtomicFile {
    fn drop(&mut self) {
        // Still open: not committed. The rename moved the file otherwise,
        // and removing a path that no longer exists is harmless.
        self.writer.take();
        if let Some(tmp) = &self.tmp {
            let _ = std::fs::remove_file(tmp);
            unregister(tmp);
        }
    }
}

/// Files written as a set (the outputs of `pcaline map`): each is written
/// and synced to its temporary file first, and only when all of them are
/// does [`OutputSet::commit`] rename them into place. A failure part-way (a
/// full disk) leaves none of them, instead of some.
#[derive(Debug, Default)]
pub struct OutputSet {
    files: Vec<AtomicFile>,
}

impl OutputSet {
    /// An empty set.
    pub fn new() -> Self {
        OutputSet::default()
    }

    /// Writes `bytes` to `path`'s temporary file and syncs it.
    pub fn add(&mut self, path: &Path, bytes: &[u8]) -> Result<(), IoError> {
        let mut file = AtomicFile::create(path)?;
        file.write_all(bytes).map_err(|e| IoError::io(path, e))?;
        file.sync()?;
        self.files.push(file);
        Ok(())
    }

    /// Renames every file into place; returns their paths, in the order
    /// they were added. A rename that fails (rare once every file is
    /// written) is an error that says which files were already in place.
    pub fn commit(self) -> Result<Vec<PathBuf>, IoError> {
        let mut done: Vec<PathBuf> = Vec::with_capacity(self.files.len());
        for file in self.files {
            let path = file.target().to_path_buf();
            if let Err(e) = file.commit() {
                return Err(match done.is_empty() {
                    true => e,
                    false => IoError::parse(
                        &path,
                        None,
                        format!(
                            "{e} (already written: {})",
                            done.iter()
                                .map(|p| p.display().to_string())
                                .collect::<Vec<_>>()
                                .join(", ")
                        ),
                    ),
                });
            }
            done.push(path);
        }
        Ok(done)
    }
}

/// Writes `bytes` to `path` atomically (temporary file in the same directory,
/// flushed and synced, then renamed over the target).
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), IoError> {
    write_atomic_with(path, |w| w.write_all(bytes))
}

/// Writes to `path` atomically through `fill`, which gets a buffered writer.
/// On any error the temporary file is removed and the target is untouched.
pub fn write_atomic_with(
    path: &Path,
    fill: impl FnOnce(&mut dyn Write) -> std::io::Result<()>,
) -> Result<(), IoError> {
    let mut file = AtomicFile::create(path)?;
    fill(&mut file).map_err(|e| IoError::io(path, e))?;
    file.commit()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn failed_write_leaves_nothing() {
        let dir = std::env::temp_dir().join(format!("pcaline-atomic-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let target = dir.join("out.json");
        let err = write_atomic_with(&target, |w| {
            w.write_all(b"partial")?;
            Err(std::io::Error::other("boom"))
        });
        assert!(err.is_err());
        assert!(!target.exists());
        assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 0, "temporary file removed");
        write_atomic(&target, b"{}").unwrap();
        assert_eq!(std::fs::read(&target).unwrap(), b"{}");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn streaming_file_seeks_and_is_removed_unless_committed() {
        let dir = std::env::temp_dir().join(format!("pcaline-atomic-seek-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let target = dir.join("out.bin");
        {
            let mut f = AtomicFile::create(&target).unwrap();
            f.write_all(b"abcdef").unwrap();
            assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 1, "only the temporary file");
        }
        assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 0, "dropped: removed");
        let mut f = AtomicFile::create(&target).unwrap();
        f.write_all(b"abcdef").unwrap();
        f.seek(SeekFrom::Start(1)).unwrap();
        f.write_all(b"X").unwrap();
        assert!(!target.exists(), "nothing at the target before the commit");
        f.commit().unwrap();
        assert_eq!(std::fs::read(&target).unwrap(), b"aXcdef");
        assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 1);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn devices_are_written_in_place_and_links_followed() {
        let dir = std::env::temp_dir().join(format!("pcaline-atomic-dev-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        // /dev/null stays a device.
        write_atomic(Path::new("/dev/null"), b"nothing").unwrap();
        let m = std::fs::metadata("/dev/null").unwrap();
        assert!(!m.is_file(), "/dev/null is still a device");
        assert!(AtomicFile::create(&dir).unwrap_err().to_string().contains("is a directory"));
        // A link to a file: the file is replaced, the link kept.
        let real = dir.join("real.json");
        std::fs::write(&real, b"old").unwrap();
        let link = dir.join("link.json");
        std::os::unix::fs::symlink(&real, &link).unwrap();
        write_atomic(&link, b"new").unwrap();
        assert!(link.is_symlink());
        assert_eq!(std::fs::read(&real).unwrap(), b"new");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn a_set_is_written_whole_or_not_at_all() {
        let dir = std::env::temp_dir().join(format!("pcaline-atomic-set-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let mut set = OutputSet::new();
        set.add(&dir.join("a.json"), b"a").unwrap();
        // The second file cannot be written: the first is not left behind.
        assert!(set.add(&dir.join("no-folder/b.json"), b"b").is_err());
        drop(set);
        assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 0, "nothing left");
        let mut set = OutputSet::new();
        set.add(&dir.join("a.json"), b"a").unwrap();
        set.add(&dir.join("b.json"), b"b").unwrap();
        assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 2, "two temporary files");
        assert!(!dir.join("a.json").exists());
        let done = set.commit().unwrap();
        assert_eq!(done, [dir.join("a.json"), dir.join("b.json")]);
        assert_eq!(std::fs::read(dir.join("b.json")).unwrap(), b"b");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn unwritable_folder_names_the_target() {
        let target = Path::new("/nonexistent-pcaline-folder/out.mcap");
        let err = AtomicFile::create(target).unwrap_err();
        assert!(err.to_string().contains("/nonexistent-pcaline-folder/out.mcap"), "{err}");
    }
}
