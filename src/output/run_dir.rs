//! Atomic run folders: staging folder + rename.
//!
//! A run folder is replaced whole, so it must hold only what groutready
//! writes: every run folder carries a marker file ([`MARKER`]) by which the
//! next run recognises it ([`kind`]), and the what-ifs the engineer saved in
//! it (`whatif/`, the next weekly input) are carried into the new folder.
//! An interrupted run leaves its hidden `.NAME.staging-PID` or
//! `.NAME.old-PID` folder next to the run folder; [`clean_stale`] removes
//! those of processes no longer alive (or puts the old folder back when the
//! run folder itself is missing).

use std::fs;
use std::io;
use std::path::{Path, PathBuf};

use super::lock::{alive, Liveness};

/// The marker file in every run folder; it holds the program's version.
pub const MARKER: &str = ".groutready-run";

/// Folder of the what-if schedule sets inside a run folder: kept across runs.
pub const WHATIF_DIR: &str = "whatif";

/// Everything groutready writes at the top of a run folder (`run` and
/// `plan`, this and earlier versions); anything else is the user's.
pub const RUN_FOLDER_NAMES: &[&str] = &[
    MARKER,
    "run.txt",
    "temperatures.csv",
    super::apertures::FILE_NAME,
    "fields",
    "readiness.csv",
    "report.json",
    "report.md",
    "charts",
    "restart",
    "remedied",
    WHATIF_DIR,
];

/// What is at a run folder's destination.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Existing {
    Missing,
    /// a folder with nothing in it
    Empty,
    /// a run folder (marked, or older: `run.txt` with `restart/` or
    /// `fields/`); `foreign` lists the entries groutready does not write
    RunFolder {
        foreign: Vec<String>,
    },
    /// a folder that is not a run folder, with its entries (`name/` for a folder)
    Foreign {
        entries: Vec<String>,
    },
    File,
    Symlink,
}

/// Entry names of `dir`, sorted, folders with a trailing `/`.
fn entries(dir: &Path) -> io::Result<Vec<String>> {
    let mut names = Vec::new();
    for e in fs::read_dir(dir)? {
        let e = e?;
        let mut name = e.file_name().to_string_lossy().into_owned();
        if e.file_type()?.is_dir() {
            name.push('/');
        }
        names.push(name);
    }
    names.sort();
    Ok(names)
}

/// What is at `dest`: nothing, an empty folder, a run folder, or something
/// groutready did not write.
pub fn kind(dest: &Path) -> io::Result<Existing> {
    let meta = match fs::symlink_metadata(dest) {
        Ok(m) => m,
        Err(e) if e.kind() == io::ErrorKind::NotFound => return Ok(Existing::Missing),
        Err(e) => return Err(e),
    };
    if meta.file_type().is_symlink() {
        return Ok(Existing::Symlink);
    }
    if !meta.is_dir() {
        return Ok(Existing::File);
    }
    let names = entries(dest)?;
    if names.is_empty() {
        return Ok(Existing::Empty);
    }
    let marked = dest.join(MARKER).is_file();
    let older = dest.join("run.txt").is_file()
        && (dest.join("restart").is_dir() || dest.join("fields").is_dir());
    if marked || older {
        let foreign = names
            .into_iter()
            .filter(|n| !RUN_FOLDER_NAMES.contains(&n.trim_end_matches('/')))
            .collect();
        Ok(Existing::RunFolder { foreign })
    } else {
        Ok(Existing::Foreign { entries: names })
    }
}

fn file_name(dest: &Path) -> String {
    dest.file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "run".into())
}

fn parent(dest: &Path) -> PathBuf {
    match dest.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    }
}

/// A run folder under construction. Dropped without [`RunDir::commit`], it
/// removes its staging folder and leaves the destination untouched.
#[derive(Debug)]
pub struct RunDir {
    staging: PathBuf,
    dest: PathBuf,
    committed: bool,
}

impl RunDir {
    pub fn create(dest: &Path) -> io::Result<RunDir> {
        let parent = parent(dest);
        fs::create_dir_all(&parent)?;
        let name = file_name(dest);
        let staging = parent.join(format!(".{name}.staging-{}", std::process::id()));
        if staging.exists() {
            fs::remove_dir_all(&staging)?;
        }
        fs::create_dir_all(&staging)?;
        let dir = RunDir {
            staging,
            dest: dest.to_path_buf(),
            committed: false,
        };
        fs::write(
            dir.staging.join(MARKER),
            format!("groutready {}\n", env!("CARGO_PKG_VERSION")),
        )?;
        Ok(dir)
    }

    /// Where files are written until commit.
    pub fn path(&self) -> &Path {
        &self.staging
    }

    pub fn dest(&self) -> &Path {
        &self.dest
    }

    /// Replaces the destination with the staged folder, the destination's
    /// `whatif/` copied in first (a copy: until the rename, the originals
    /// stay where they were).
    pub fn commit(mut self) -> io::Result<PathBuf> {
        let old = self.dest.with_file_name(format!(
            ".{}.old-{}",
            file_name(&self.dest),
            std::process::id()
        ));
        let whatif = self.dest.join(WHATIF_DIR);
        if whatif.is_dir() && !self.dest.is_symlink() {
            copy_tree(&whatif, &self.staging.join(WHATIF_DIR))?;
        }
        let had_old = fs::symlink_metadata(&self.dest).is_ok();
        if had_old {
            fs::rename(&self.dest, &old)?;
        }
        if let Err(e) = fs::rename(&self.staging, &self.dest) {
            if had_old {
                let _ = fs::rename(&old, &self.dest);
            }
            return Err(e);
        }
        if had_old {
            let _ = remove_any(&old);
        }
        self.committed = true;
        Ok(self.dest.clone())
    }
}

impl Drop for RunDir {
    fn drop(&mut self) {
        if !self.committed {
            let _ = fs::remove_dir_all(&self.staging);
        }
    }
}

/// Removes a folder with its contents, or a file or link.
fn remove_any(path: &Path) -> io::Result<()> {
    let meta = fs::symlink_metadata(path)?;
    if meta.is_dir() {
        fs::remove_dir_all(path)
    } else {
        fs::remove_file(path)
    }
}

/// Copies the folder `from` to `to` (created), recursively; links are not followed.
fn copy_tree(from: &Path, to: &Path) -> io::Result<()> {
    fs::create_dir_all(to)?;
    for e in fs::read_dir(from)? {
        let e = e?;
        let kind = e.file_type()?;
        let target = to.join(e.file_name());
        if kind.is_dir() {
            copy_tree(&e.path(), &target)?;
        } else if kind.is_file() {
            fs::copy(e.path(), &target)?;
        }
    }
    Ok(())
}

/// The process id of an interrupted run's `.NAME.staging-PID` or
/// `.NAME.old-PID` entry of the run folder named `name`, and whether it is
/// the old folder.
fn leftover_pid(entry: &str, name: &str) -> Option<(u32, bool)> {
    let rest = entry.strip_prefix('.')?.strip_prefix(name)?;
    if let Some(pid) = rest.strip_prefix(".staging-") {
        return pid.parse().ok().map(|p| (p, false));
    }
    rest.strip_prefix(".old-")?.parse().ok().map(|p| (p, true))
}

/// Removes the staging and old folders that interrupted runs into `dest`
/// left next to it, those of processes known to be dead only; an old folder
/// whose run folder is missing (the run was stopped between its two
/// renames) is put back instead. Returns what was done, one line each.
pub fn clean_stale(dest: &Path) -> io::Result<Vec<String>> {
    let parent = parent(dest);
    let name = file_name(dest);
    let mut done = Vec::new();
    let rd = match fs::read_dir(&parent) {
        Ok(rd) => rd,
        Err(e) if e.kind() == io::ErrorKind::NotFound => return Ok(done),
        Err(e) => return Err(e),
    };
    let mut found: Vec<(PathBuf, u32, bool)> = rd
        .filter_map(|e| e.ok())
        .filter_map(|e| {
            let entry = e.file_name().to_string_lossy().into_owned();
            leftover_pid(&entry, &name).map(|(pid, old)| (e.path(), pid, old))
        })
        .filter(|(_, pid, _)| *pid != std::process::id())
        .collect();
    found.sort();
    for (path, pid, old) in found {
        if alive(pid, None) != Liveness::Dead {
            continue;
        }
        let what = if old {
            "old run folder"
        } else {
            "unfinished run"
        };
        if old && fs::symlink_metadata(dest).is_err() {
            fs::rename(&path, dest)?;
            done.push(format!(
                "put back {} from {} (a run by process {pid}, no longer running, stopped while replacing it)",
                dest.display(),
                path.display()
            ));
            continue;
        }
        remove_any(&path)?;
        done.push(format!(
            "removed {} (the {what} of process {pid}, no longer running)",
            path.display()
        ));
    }
    Ok(done)
}

#[cfg(test)]
mod tests {
    use super::leftover_pid;

    #[test]
    fn leftovers_are_recognised_by_name_and_pid() {
        assert_eq!(leftover_pid(".r.staging-12", "r"), Some((12, false)));
        assert_eq!(leftover_pid(".r.old-7", "r"), Some((7, true)));
        assert_eq!(leftover_pid(".rr.old-7", "r"), None);
        assert_eq!(leftover_pid(".r.old-x", "r"), None);
        assert_eq!(leftover_pid("r.old-7", "r"), None);
    }
}
