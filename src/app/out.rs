//! Where a run may write (`--out`). A run folder replaces its destination
//! whole, so before anything is simulated the destination must be missing,
//! an empty folder, or an earlier run folder (recognised by its marker, see
//! [`crate::output::run_dir`]); anything else, a file or a folder of the
//! site's documents, is refused unless the caller forces it. Never, even
//! forced: the current folder or one of its parents, a folder holding the
//! scene or the schedules, or one that cannot be written. The folder is
//! then locked ([`crate::output::lock`]) and the leftovers of interrupted
//! runs into it cleaned, all before the first step is simulated, so a
//! refusal costs nothing and a weekly job on a shared drive never destroys
//! what it did not write.

use std::io;
use std::path::{Component, Path, PathBuf};

use crate::output::lock::{LockFailure, RunLock};
use crate::output::run_dir::{self, Existing, WHATIF_DIR};

use super::Inputs;

/// Why a run may not write where it was asked to. Every message starts with
/// the path as given.
#[derive(Debug, thiserror::Error)]
pub enum OutError {
    #[error("{path}: holds {what} groutready did not write ({names}); give --out a new or empty folder or an earlier run folder, or add --force to replace it")]
    Foreign {
        path: String,
        what: String,
        names: String,
    },
    #[error("{path}: is a run folder, but also holds {what} groutready did not write ({names}); move them out, or add --force to replace the folder with them")]
    ForeignInRunFolder {
        path: String,
        what: String,
        names: String,
    },
    #[error(
        "{path}: is a file, not a folder; give --out a folder, or add --force to replace the file"
    )]
    IsFile { path: String },
    #[error("{path}: is a symbolic link; give --out the folder itself, or add --force to replace the link")]
    IsLink { path: String },
    #[error("{path}: is the schedules folder; a run folder would replace the schedules (give --out another folder)")]
    IsSchedules { path: String },
    #[error("{path}: contains the schedules folder {schedules}; a run folder would replace it (give --out another folder)")]
    ContainsSchedules { path: String, schedules: String },
    #[error("{path}: contains the scene {scene}; a run folder would replace it (give --out another folder)")]
    ContainsScene { path: String, scene: String },
    #[error("{path}: is the current folder or one of its parents ({cwd}); a run folder would replace it (give --out a folder inside it, e.g. runs/NAME)")]
    IsCurrentDir { path: String, cwd: String },
    #[error("{path}: cannot be written: {why}")]
    NotWritable { path: String, why: String },
    #[error(
        "{path}: is being written by {holder} (lock file {lock}); wait for that run to finish"
    )]
    Locked {
        path: String,
        holder: String,
        lock: String,
    },
    #[error("{path}: is locked by {holder} (lock file {lock}), which cannot be checked from this machine; if no groutready runs there, delete the lock file")]
    LockedElsewhere {
        path: String,
        holder: String,
        lock: String,
    },
    #[error("{path}: {source}")]
    Io { path: String, source: io::Error },
}

/// A run folder's destination, checked and locked: what [`super::run`] and
/// [`super::plan::plan`] write into. Dropping it releases the lock.
#[derive(Debug)]
pub struct OutDir {
    given: PathBuf,
    dest: PathBuf,
    lock: RunLock,
    notes: Vec<String>,
}

impl OutDir {
    /// Checks that a run of `inputs` may write the run folder `out`, locks
    /// it and cleans what interrupted runs into it left. `force` allows
    /// replacing a file, a link or a folder groutready did not write.
    pub fn prepare(out: &Path, inputs: &Inputs, force: bool) -> Result<OutDir, OutError> {
        let shown = out.display().to_string();
        let io = |source: io::Error| OutError::Io {
            path: shown.clone(),
            source,
        };
        let dest = resolve(out).map_err(io)?;
        check_inputs(&shown, &dest, inputs)?;
        let parent = dest.parent().unwrap_or(&dest).to_path_buf();
        check_writable(&shown, &nearest_existing(&parent))?;
        std::fs::create_dir_all(&parent).map_err(io)?;
        let name = dest.file_name().unwrap_or_default().to_string_lossy();
        let lock_path = parent.join(format!(".{name}.lock"));
        let (lock, previous) = RunLock::acquire(&lock_path).map_err(|e| match e {
            LockFailure::Held { holder, elsewhere } => {
                let (path, lock) = (shown.clone(), lock_path.display().to_string());
                if elsewhere {
                    OutError::LockedElsewhere { path, holder, lock }
                } else {
                    OutError::Locked { path, holder, lock }
                }
            }
            LockFailure::Io(source) => OutError::Io {
                path: lock_path.display().to_string(),
                source,
            },
        })?;
        let mut notes = Vec::new();
        if let Some(h) = previous {
            notes.push(format!(
                "took over the lock {} left by {h}, which is not running any more",
                lock_path.display()
            ));
        }
        notes.extend(run_dir::clean_stale(&dest).map_err(io)?);
        check_existing(&shown, &dest, force)?;
        Ok(OutDir {
            given: out.to_path_buf(),
            dest,
            lock,
            notes,
        })
    }

    /// The run folder as the caller gave it.
    pub fn path(&self) -> &Path {
        &self.given
    }

    /// The run folder as an absolute path (what is written).
    pub fn dest(&self) -> &Path {
        &self.dest
    }

    /// The lock file held.
    pub fn lock_path(&self) -> &Path {
        self.lock.path()
    }

    /// What was cleaned or taken over on the way in, one line each (the
    /// caller says so to the user).
    pub fn notes(&self) -> &[String] {
        &self.notes
    }
}

/// `p` as an absolute path: its folder with links resolved, its own name
/// as given (a link at `p` stays a link).
fn resolve(p: &Path) -> io::Result<PathBuf> {
    let abs = std::path::absolute(p)?;
    match (abs.parent(), abs.file_name()) {
        (Some(parent), Some(name)) => Ok(canonical(parent)?.join(name)),
        _ => canonical(&abs),
    }
}

/// `p` with links resolved as far as it exists; the rest applied as written.
fn canonical(p: &Path) -> io::Result<PathBuf> {
    let abs = std::path::absolute(p)?;
    for base in abs.ancestors() {
        let Ok(mut out) = base.canonicalize() else {
            continue;
        };
        for c in abs.strip_prefix(base).unwrap_or(Path::new("")).components() {
            match c {
                Component::Normal(n) => out.push(n),
                Component::ParentDir => {
                    out.pop();
                }
                _ => {}
            }
        }
        return Ok(out);
    }
    Ok(abs)
}

/// `p` both as a path (a link where it is) and with links resolved.
fn both(p: &Path) -> Vec<PathBuf> {
    [resolve(p), p.canonicalize()]
        .into_iter()
        .filter_map(Result::ok)
        .collect()
}

/// The refusals no `--force` lifts: the current folder or a parent of it,
/// the scene inside, the schedules folder or a folder containing it (except
/// the run folder's own `whatif/`, which is carried over).
fn check_inputs(shown: &str, dest: &Path, inputs: &Inputs) -> Result<(), OutError> {
    let path = shown.to_string();
    if let Ok(cwd) = std::env::current_dir().and_then(|c| c.canonicalize()) {
        if cwd.starts_with(dest) {
            let cwd = cwd.display().to_string();
            return Err(OutError::IsCurrentDir { path, cwd });
        }
    }
    if both(&inputs.scene_path).iter().any(|s| s.starts_with(dest)) {
        let scene = inputs.scene_path.display().to_string();
        return Err(OutError::ContainsScene { path, scene });
    }
    let whatif = dest.join(WHATIF_DIR);
    for s in both(&inputs.schedules_dir) {
        if s == dest {
            return Err(OutError::IsSchedules { path });
        }
        if s.starts_with(dest) && !s.starts_with(&whatif) {
            let schedules = inputs.schedules_dir.display().to_string();
            return Err(OutError::ContainsSchedules { path, schedules });
        }
    }
    Ok(())
}

/// The first of `p` and its parents that exists.
fn nearest_existing(p: &Path) -> PathBuf {
    p.ancestors()
        .find(|a| std::fs::symlink_metadata(a).is_ok())
        .unwrap_or(p)
        .to_path_buf()
}

/// Refuses a folder marked read-only (even for a user, such as root, the
/// system would let write) or in which no file can be created.
fn check_writable(shown: &str, dir: &Path) -> Result<(), OutError> {
    let fail = |why: String| OutError::NotWritable {
        path: shown.to_string(),
        why,
    };
    let meta = std::fs::metadata(dir).map_err(|e| fail(format!("{}: {e}", dir.display())))?;
    if !meta.is_dir() {
        return Err(fail(format!("{} is not a folder", dir.display())));
    }
    // Windows marks folders read-only for other reasons: the probe decides there.
    if cfg!(unix) && meta.permissions().readonly() {
        return Err(fail(format!("{} is read-only", dir.display())));
    }
    let probe = dir.join(format!(".groutready-probe-{}", std::process::id()));
    match std::fs::File::create(&probe) {
        Ok(_) => {
            let _ = std::fs::remove_file(&probe);
            Ok(())
        }
        Err(e) => Err(fail(format!(
            "cannot create a file in {}: {e}",
            dir.display()
        ))),
    }
}

/// "3 files", "1 file and 2 folders", with up to five of their names.
fn describe(entries: &[String]) -> (String, String) {
    let folders = entries.iter().filter(|e| e.ends_with('/')).count();
    let files = entries.len() - folders;
    let count = |n: usize, one: &str| format!("{n} {one}{}", if n == 1 { "" } else { "s" });
    let what = match (files, folders) {
        (f, 0) => count(f, "file"),
        (0, d) => count(d, "folder"),
        (f, d) => format!("{} and {}", count(f, "file"), count(d, "folder")),
    };
    let mut names = entries
        .iter()
        .take(5)
        .cloned()
        .collect::<Vec<_>>()
        .join(", ");
    if entries.len() > 5 {
        names.push_str(", …");
    }
    (what, names)
}

/// Refuses what is at `dest` unless it is nothing, an empty folder or a run
/// folder of groutready's files only (or `force`); then an existing folder
/// must be writable (the probe's file is made only once the folder is
/// accepted).
fn check_existing(shown: &str, dest: &Path, force: bool) -> Result<(), OutError> {
    let path = shown.to_string();
    let found = run_dir::kind(dest).map_err(|source| OutError::Io {
        path: path.clone(),
        source,
    })?;
    let refusal = match &found {
        Existing::Missing | Existing::Empty => None,
        Existing::RunFolder { foreign } if foreign.is_empty() => None,
        Existing::RunFolder { foreign } => {
            let (what, names) = describe(foreign);
            Some(OutError::ForeignInRunFolder { path, what, names })
        }
        Existing::Foreign { entries } => {
            let (what, names) = describe(entries);
            Some(OutError::Foreign { path, what, names })
        }
        Existing::File => Some(OutError::IsFile { path }),
        Existing::Symlink => Some(OutError::IsLink { path }),
    };
    match refusal {
        Some(e) if !force => Err(e),
        _ => match found {
            Existing::Empty | Existing::RunFolder { .. } | Existing::Foreign { .. } => {
                check_writable(shown, dest)
            }
            Existing::Missing | Existing::File | Existing::Symlink => Ok(()),
        },
    }
}

#[cfg(test)]
mod tests {
    use super::describe;

    #[test]
    fn foreign_entries_are_counted_and_named() {
        let e = |v: &[&str]| v.iter().map(|s| s.to_string()).collect::<Vec<_>>();
        assert_eq!(
            describe(&e(&["a.txt", "b.txt", "c.txt"])),
            ("3 files".into(), "a.txt, b.txt, c.txt".into())
        );
        assert_eq!(
            describe(&e(&["a.txt", "docs/"])),
            ("1 file and 1 folder".into(), "a.txt, docs/".into())
        );
        let many = e(&["1", "2", "3", "4", "5", "6"]);
        assert_eq!(describe(&many).1, "1, 2, 3, 4, 5, …");
    }
}
