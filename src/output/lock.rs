//! The lock on a run folder: two plans into the same folder at once would
//! each replace the other's work, and the last one would win silently.
//!
//! The lock is a file `.NAME.lock` next to the run folder, held with an
//! exclusive [`File::try_lock`] (released by the system when the process
//! dies, however it dies) and holding who took it: process id, host, when,
//! and the process's start time on Linux (so a recycled process id is not
//! mistaken for the holder). The file is removed when the lock is dropped.
//! A lock file left by a process that is not running any more (killed) is
//! taken over; one that names a live process is respected even where the
//! file lock itself is not seen (a shared drive), and so is one that names
//! another host, whose processes cannot be checked from here.
//!
//! The clock is read only to say when a lock was taken, never for what is
//! simulated or planned.

use std::fs::{File, OpenOptions, TryLockError};
use std::io::{self, Read, Seek, Write};
use std::path::{Path, PathBuf};

/// Whether a process is running, as far as this system can tell.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Liveness {
    Alive,
    Dead,
    /// not knowable here (no `/proc`): callers assume it may be alive
    Unknown,
}

/// The start time of process `pid` in clock ticks since boot (Linux).
fn start_ticks(pid: u32) -> Option<u64> {
    let stat = std::fs::read_to_string(format!("/proc/{pid}/stat")).ok()?;
    // The command name, in parentheses, may hold spaces: fields count from
    // the last ')'; the start time is field 22, the 20th after it.
    let rest = &stat[stat.rfind(')')? + 1..];
    rest.split_whitespace().nth(19)?.parse().ok()
}

/// Whether process `pid` runs, and is the one started at `start` (clock
/// ticks since boot) when given.
pub fn alive(pid: u32, start: Option<u64>) -> Liveness {
    if !cfg!(target_os = "linux") || !Path::new("/proc/self").exists() {
        return Liveness::Unknown;
    }
    if !Path::new(&format!("/proc/{pid}")).exists() {
        return Liveness::Dead;
    }
    match (start, start_ticks(pid)) {
        (Some(want), Some(got)) if want != got => Liveness::Dead,
        _ => Liveness::Alive,
    }
}

/// This machine's name, as far as the system says it.
pub fn host_name() -> String {
    let from_file = |p: &str| {
        std::fs::read_to_string(p)
            .ok()
            .map(|s| s.trim().to_string())
    };
    from_file("/proc/sys/kernel/hostname")
        .or_else(|| from_file("/etc/hostname"))
        .or_else(|| std::env::var("COMPUTERNAME").ok())
        .or_else(|| std::env::var("HOSTNAME").ok())
        .filter(|s| !s.is_empty())
        .unwrap_or_else(|| "unknown host".into())
}

/// Who holds (or held) a lock, as written in its file.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Holder {
    pub pid: u32,
    pub host: String,
    /// when the lock was taken (UTC, as written)
    pub started: String,
    /// the process's start time in clock ticks since boot (Linux)
    pub start_ticks: Option<u64>,
}

impl Holder {
    /// This process, now.
    pub fn me() -> Holder {
        let now: chrono::DateTime<chrono::Utc> = std::time::SystemTime::now().into();
        Holder {
            pid: std::process::id(),
            host: host_name(),
            started: now.format("%Y-%m-%d %H:%M:%S UTC").to_string(),
            start_ticks: start_ticks(std::process::id()),
        }
    }

    /// The lock file's text.
    pub fn to_text(&self) -> String {
        let mut s = format!(
            "pid = {}\nhost = {}\nstarted = {}\n",
            self.pid, self.host, self.started
        );
        if let Some(t) = self.start_ticks {
            s += &format!("start_ticks = {t}\n");
        }
        s
    }

    /// Reads a lock file's text; None when it names no process.
    pub fn parse(text: &str) -> Option<Holder> {
        let mut h = Holder {
            pid: 0,
            host: String::new(),
            started: String::new(),
            start_ticks: None,
        };
        for line in text.lines() {
            let Some((k, v)) = line.split_once('=') else {
                continue;
            };
            let v = v.trim();
            match k.trim() {
                "pid" => h.pid = v.parse().ok()?,
                "host" => h.host = v.to_string(),
                "started" => h.started = v.to_string(),
                "start_ticks" => h.start_ticks = v.parse().ok(),
                _ => {}
            }
        }
        (h.pid != 0).then_some(h)
    }
}

impl std::fmt::Display for Holder {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "process {} on {}", self.pid, self.host)?;
        if !self.started.is_empty() {
            write!(f, " since {}", self.started)?;
        }
        Ok(())
    }
}

/// Why a lock could not be taken.
#[derive(Debug)]
pub enum LockFailure {
    /// held by a running process (or one on another host)
    Held {
        holder: String,
        elsewhere: bool,
    },
    Io(io::Error),
}

impl From<io::Error> for LockFailure {
    fn from(e: io::Error) -> Self {
        LockFailure::Io(e)
    }
}

/// A held lock; dropping it removes the lock file and releases the lock.
#[derive(Debug)]
pub struct RunLock {
    path: PathBuf,
    file: File,
}

/// Whether `file` is still the file at `path` (not removed and replaced by
/// the holder that released it while this process waited on it).
#[cfg(unix)]
fn same_file(file: &File, path: &Path) -> io::Result<bool> {
    use std::os::unix::fs::MetadataExt;
    let (a, b) = (file.metadata()?, std::fs::metadata(path));
    Ok(b.is_ok_and(|b| a.ino() == b.ino() && a.dev() == b.dev()))
}

#[cfg(not(unix))]
fn same_file(_: &File, path: &Path) -> io::Result<bool> {
    Ok(path.exists())
}

impl RunLock {
    /// Takes the lock file `path`. Returns the lock and, when it took over
    /// a lock file left by a process that is not running, that holder.
    pub fn acquire(path: &Path) -> Result<(RunLock, Option<Holder>), LockFailure> {
        for _ in 0..5 {
            let mut file = OpenOptions::new()
                .read(true)
                .write(true)
                .create(true)
                .truncate(false)
                .open(path)?;
            let mut text = String::new();
            match file.try_lock() {
                Ok(()) => {}
                Err(TryLockError::WouldBlock) => {
                    file.read_to_string(&mut text)?;
                    let holder = Holder::parse(&text)
                        .map_or_else(|| "another process".to_string(), |h| h.to_string());
                    return Err(LockFailure::Held {
                        holder,
                        elsewhere: false,
                    });
                }
                // No file locks here: the holder written in the file decides.
                Err(TryLockError::Error(e)) if e.kind() == io::ErrorKind::Unsupported => {}
                Err(TryLockError::Error(e)) => return Err(e.into()),
            }
            if !same_file(&file, path)? {
                continue;
            }
            file.read_to_string(&mut text)?;
            let previous = Holder::parse(&text);
            if let Some(h) = &previous {
                check_previous(h)?;
            }
            file.set_len(0)?;
            file.rewind()?;
            file.write_all(Holder::me().to_text().as_bytes())?;
            file.sync_all()?;
            let lock = RunLock {
                path: path.to_path_buf(),
                file,
            };
            return Ok((lock, previous));
        }
        Err(LockFailure::Io(io::Error::other(
            "the lock file keeps being replaced by other processes",
        )))
    }

    pub fn path(&self) -> &Path {
        &self.path
    }
}

/// Refuses a lock file that names a process that may still be running:
/// alive here, or on another host.
fn check_previous(h: &Holder) -> Result<(), LockFailure> {
    let me = Holder::me();
    if h.pid == me.pid && h.host == me.host {
        return Ok(());
    }
    if h.host != me.host {
        return Err(LockFailure::Held {
            holder: h.to_string(),
            elsewhere: true,
        });
    }
    match alive(h.pid, h.start_ticks) {
        Liveness::Dead => Ok(()),
        // The file lock was free: with no way to see the process, trust it.
        Liveness::Unknown => Ok(()),
        Liveness::Alive => Err(LockFailure::Held {
            holder: h.to_string(),
            elsewhere: false,
        }),
    }
}

impl Drop for RunLock {
    fn drop(&mut self) {
        // Removed while still locked; a process waiting on the old file
        // sees it is not the file at `path` any more and opens again.
        let _ = std::fs::remove_file(&self.path);
        let _ = self.file.unlock();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn holder_text_round_trips() {
        let h = Holder {
            pid: 42,
            host: "site-pc".into(),
            started: "2024-05-20 06:00:00 UTC".into(),
            start_ticks: Some(123),
        };
        assert_eq!(Holder::parse(&h.to_text()), Some(h.clone()));
        assert_eq!(
            h.to_string(),
            "process 42 on site-pc since 2024-05-20 06:00:00 UTC"
        );
        assert_eq!(Holder::parse("nothing"), None);
    }

    #[test]
    fn this_process_is_alive() {
        let me = Holder::me();
        if cfg!(target_os = "linux") {
            assert_eq!(alive(me.pid, me.start_ticks), Liveness::Alive);
            assert_eq!(alive(me.pid, me.start_ticks.map(|t| t + 1)), Liveness::Dead);
        }
    }
}
