//! The output directory of a run: one run at a time (a lock file), and the files an earlier
//! run wrote removed on `--force` (and only those).

use std::path::{Path, PathBuf};

use crate::OutputError;

/// The lock file of a running output directory (it holds the process id).
pub const LOCK_FILE: &str = ".mpm.lock";

/// The files a run writes into its output directory (besides `frames/particles_*.vtp` and
/// temporary `.NAME.tmp-PID.EXT` files): what `--force` removes.
const RUN_FILES: [&str; 18] = [
    "scene.toml",
    "summary.json",
    "particles.pvd",
    "energy.csv",
    "probes.csv",
    "runout.csv",
    "walls.csv",
    "envelope.csv",
    "deposit.csv",
    "section.geojson",
    crate::checkpoint::FILE_NAME,
    "plots/energy.png",
    "plots/probes.png",
    "plots/runout.png",
    "plots/deposit.png",
    "plots/envelope.png",
    "maps/outlines.geojson",
    "maps/hazard_map.png",
];

/// One run per output directory: a lock file created atomically (a hard link of a file that
/// already holds the process id, which fails if the lock exists; where the file system has no
/// hard links, an exclusive create) and removed when the run ends. A lock whose process no
/// longer exists (a run killed with SIGKILL) is taken over: renamed aside, which only one process
/// can do, and checked to be the stale one before it is deleted. A lock holding this process's
/// own id is stale unless this process holds it now (a restarted container often gets the same
/// pid as the run it replaces).
pub struct DirLock {
    path: PathBuf,
}

/// The locks this process holds (a library user may start runs from several threads).
static HELD: std::sync::Mutex<Vec<PathBuf>> = std::sync::Mutex::new(Vec::new());

impl DirLock {
    /// takes the lock of `dir` (which must exist), or names the process holding it.
    pub fn acquire(dir: &Path) -> Result<Self, OutputError> {
        let path = dir.join(LOCK_FILE);
        let pid = std::process::id();
        let mine = dir.join(format!("{LOCK_FILE}.{pid}"));
        std::fs::write(&mine, format!("{pid}\n"))
            .map_err(|source| OutputError::Io { path: mine.clone(), source })?;
        let locked = |holder: Option<u32>| {
            Err(OutputError::Locked { dir: dir.to_path_buf(), lock: path.clone(), pid: holder })
        };
        let mut result = locked(None);
        // A few attempts: after taking over a stale lock, or when the holder ended meanwhile.
        for _ in 0..4 {
            let linked = match std::fs::hard_link(&mine, &path) {
                Err(e) if e.kind() != std::io::ErrorKind::AlreadyExists => {
                    // no hard links here: an exclusive create, then the pid
                    std::fs::OpenOptions::new().write(true).create_new(true).open(&path).and_then(
                        |mut f| std::io::Write::write_all(&mut f, format!("{pid}\n").as_bytes()),
                    )
                }
                other => other,
            };
            match linked {
                Ok(()) => {
                    if let Ok(mut held) = HELD.lock() {
                        held.push(path.clone());
                    }
                    result = Ok(DirLock { path: path.clone() });
                    break;
                }
                Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => {
                    let (holder, readable) = match std::fs::read_to_string(&path) {
                        Ok(text) => (text.trim().parse::<u32>().ok(), true),
                        // the holder ended between our attempt and the read: try again
                        Err(e) if e.kind() == std::io::ErrorKind::NotFound => continue,
                        // unreadable (another user's lock): its holder is unknown, never stale
                        Err(_) => (None, false),
                    };
                    // a lock to take over: naming a process that is gone, or naming none (read,
                    // but empty or garbled) and older than a writer needs to fill it in
                    let takeover = match holder {
                        Some(other) if stale(other, &path) => true,
                        None => readable && abandoned(&path),
                        Some(_) => false,
                    };
                    match holder {
                        other if takeover => {
                            let aside = dir.join(format!("{LOCK_FILE}.stale-{pid}"));
                            if std::fs::rename(&path, &aside).is_ok() {
                                let moved = std::fs::read_to_string(&aside)
                                    .ok()
                                    .and_then(|t| t.trim().parse::<u32>().ok());
                                // (what was moved must be the lock judged stale: the same id,
                                // or, naming none, still as old: a rename keeps the time, so a
                                // fresh empty lock another run just made is told apart)
                                if moved != other || (other.is_none() && !abandoned(&aside)) {
                                    // another process took the stale lock over first and this
                                    // moved its live one: put it back
                                    let _ = std::fs::rename(&aside, &path);
                                    result = locked(moved);
                                    break;
                                }
                                let _ = std::fs::remove_file(&aside);
                            }
                        }
                        other => {
                            result = locked(other);
                            break;
                        }
                    }
                }
                Err(source) => {
                    result = Err(OutputError::Io { path: path.clone(), source });
                    break;
                }
            }
        }
        let _ = std::fs::remove_file(&mine);
        result
    }
}

impl Drop for DirLock {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.path);
        if let Ok(mut held) = HELD.lock() {
            held.retain(|p| p != &self.path);
        }
    }
}

/// A lock file that names no process is being written if it is younger than this (the
/// exclusive-create fallback writes the id right after creating it), abandoned if older.
const LOCK_WRITE_GRACE: std::time::Duration = std::time::Duration::from_secs(2);

/// whether a lock at `path` that names no process (empty or garbled: a crash between creating
/// and writing it, a disk that filled, a user's `touch`) is older than [`LOCK_WRITE_GRACE`].
fn abandoned(path: &Path) -> bool {
    std::fs::metadata(path)
        .and_then(|m| m.modified())
        .is_ok_and(|t| t.elapsed().is_ok_and(|age| age > LOCK_WRITE_GRACE))
}

/// whether a lock at `path` naming process `pid` is stale: that process does not exist, or it
/// is this process and this process does not hold the lock. Where `/proc` does not exist, every
/// other process counts as alive (the message then tells the user how to remove a stale lock).
fn stale(pid: u32, path: &Path) -> bool {
    if pid == std::process::id() {
        return HELD.lock().is_ok_and(|held| !held.iter().any(|p| p == path));
    }
    let proc = Path::new("/proc");
    proc.is_dir() && !proc.join(pid.to_string()).exists()
}

/// locks `dir` (creating it) and refuses it if it holds anything unless `force`, in which case
/// the files an earlier run wrote are removed (and only those); creates the layout.
pub fn prepare_dir(dir: &Path, force: bool) -> Result<DirLock, OutputError> {
    let io = |path: &Path| {
        let path = path.to_path_buf();
        move |source| OutputError::Io { path, source }
    };
    std::fs::create_dir_all(dir).map_err(io(dir))?;
    let lock = DirLock::acquire(dir)?;
    let non_empty = std::fs::read_dir(dir)
        .map_err(io(dir))?
        .flatten()
        .any(|e| !e.file_name().to_string_lossy().starts_with(LOCK_FILE));
    if non_empty && !force {
        return Err(OutputError::OutputExists(dir.to_path_buf()));
    }
    if force {
        remove_run_files(dir);
    }
    layout(dir)?;
    Ok(lock)
}

/// creates the sub-directories a run writes into (`frames/`, `plots/`), also when a resumed
/// run's were deleted.
pub fn layout(dir: &Path) -> Result<(), OutputError> {
    for d in [dir.join("frames"), dir.join("plots")] {
        std::fs::create_dir_all(&d)
            .map_err(|source| OutputError::Io { path: d.clone(), source })?;
    }
    Ok(())
}

/// removes what a run writes into `dir` (see [`RUN_FILES`]), leaving anything else.
fn remove_run_files(dir: &Path) {
    for name in RUN_FILES {
        let _ = std::fs::remove_file(dir.join(name));
    }
    for (name, _) in crate::maps::MAPS {
        for ext in ["asc", "tif", "prj"] {
            let _ = std::fs::remove_file(dir.join("maps").join(format!("{name}.{ext}")));
        }
    }
    for sub in [dir.to_path_buf(), dir.join("frames"), dir.join("plots"), dir.join("maps")] {
        let Ok(entries) = std::fs::read_dir(&sub) else { continue };
        for e in entries.flatten() {
            let name = e.file_name().to_string_lossy().into_owned();
            let frame =
                sub.ends_with("frames") && name.starts_with("particles_") && name.ends_with(".vtp");
            if frame || (name.starts_with('.') && name.contains(".tmp-")) {
                let _ = std::fs::remove_file(e.path());
            }
        }
    }
}
