//! Output files and folders: atomic writes, symlinks written through, one run per output
//! folder (a lock), a staging folder swapped in at the end, and what died runs left behind.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::atomic::Ordering;

use anyhow::{Context, Result, bail};

use super::interrupt::*;

/// Where writing `path` must go: the path itself, or, through any symlinks, the file they point
/// to. A folder, FIFO, socket or device is refused (writing would replace the node).
pub fn output_target(path: &Path) -> Result<PathBuf> {
    let mut p = path.to_path_buf();
    for _ in 0..40 {
        match std::fs::symlink_metadata(&p) {
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(p),
            Err(e) => return Err(e).with_context(|| format!("cannot write {}", path.display())),
            Ok(m) if m.file_type().is_symlink() => {
                let t = std::fs::read_link(&p).with_context(|| format!("cannot read the link {}", p.display()))?;
                p = match p.parent() {
                    Some(dir) if t.is_relative() => dir.join(t),
                    _ => t,
                };
            }
            Ok(m) if m.is_file() => return Ok(p),
            Ok(m) => {
                let ft = m.file_type();
                #[cfg(unix)]
                let kind = {
                    use std::os::unix::fs::FileTypeExt;
                    if ft.is_fifo() {
                        "a FIFO"
                    } else if ft.is_char_device() || ft.is_block_device() {
                        "a device"
                    } else if ft.is_socket() {
                        "a socket"
                    } else if ft.is_dir() {
                        "a folder"
                    } else {
                        "not a regular file"
                    }
                };
                #[cfg(not(unix))]
                let kind = if ft.is_dir() { "a folder" } else { "not a regular file" };
                let via = if p == path { String::new() } else { format!(" (the link's target {})", p.display()) };
                bail!("{}{via} is {kind}: refusing to write there; name a regular file", path.display());
            }
        }
    }
    bail!("{}: too many levels of symbolic links", path.display())
}

/// Writes `bytes` to `path` atomically: into a temporary file in the same folder, then renamed,
/// so a failure never leaves a half-written output. Creates the parent folder if needed. A
/// symlink is written through (its target is replaced, the link stays); folders, FIFOs, sockets
/// and devices are refused ([`output_target`]). Ctrl-C removes the temporary file.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    write_atomic_with(path, |w| Ok(w.write_all(bytes)?))
}

/// As [`write_atomic`], the bytes written by `fill` into a buffered writer (a large output is
/// never held whole in memory).
///
/// # Errors
/// As [`write_atomic`], and `fill`'s.
pub fn write_atomic_with(path: &Path, fill: impl FnOnce(&mut dyn Write) -> Result<()>) -> Result<()> {
    let target = output_target(path)?;
    let path = target.as_path();
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    // Held until the file is in place: Ctrl-C never removes a staging folder while this
    // re-creates it.
    let _gate = output_gate();
    std::fs::create_dir_all(dir).with_context(|| format!("cannot create folder {}", dir.display()))?;
    let mut tmp = tempfile::NamedTempFile::new_in(dir)
        .with_context(|| format!("cannot create a temporary file in {}", dir.display()))?;
    let _guard = TempGuard::new(tmp.path());
    {
        let mut w = std::io::BufWriter::new(tmp.as_file_mut());
        fill(&mut w).and_then(|()| Ok(w.flush()?)).with_context(|| format!("cannot write {}", path.display()))?;
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        // Temporary files are created private; outputs get the usual permissions.
        let _ = tmp.as_file().set_permissions(std::fs::Permissions::from_mode(0o644));
    }
    tmp.persist(path).with_context(|| format!("cannot write {}", path.display()))?;
    Ok(())
}

// Output folders: a lock per output, a staging folder swapped in at the end, and the leftovers
// of runs that died on the way (docs/sheet.md, "Output folders").

/// The folder that holds `out` (`.` for a bare name).
fn parent_of(out: &Path) -> PathBuf {
    match out.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    }
}

/// The last component of `out`, for the hidden names beside it.
fn name_of(out: &Path) -> String {
    out.file_name().map_or("out".into(), |n| n.to_string_lossy().into_owned())
}

/// Whether process `pid` still runs. Only Linux can tell (`/proc`); elsewhere every process is
/// taken to run, so nothing another run left is ever removed.
fn process_alive(pid: u32) -> bool {
    if cfg!(target_os = "linux") { Path::new("/proc").join(pid.to_string()).exists() } else { true }
}

/// A test hook, read only in debug builds (the tests' binary) from `MAOBI_TEST_HOOK`:
/// `fail:STEP` makes `step` fail as a full disk would; `pause:STEP` creates the file named by
/// `MAOBI_TEST_HOOK_MARKER` and waits (at most 60 s) until the test removes it or a signal
/// arrives. Release builds ignore both.
pub fn test_hook(step: &str) -> Result<()> {
    if !cfg!(debug_assertions) {
        return Ok(());
    }
    let Ok(hook) = std::env::var("MAOBI_TEST_HOOK") else { return Ok(()) };
    if hook.strip_prefix("fail:") == Some(step) {
        bail!("{step}: No space left on device (injected by MAOBI_TEST_HOOK)");
    }
    if hook.strip_prefix("pause:") == Some(step) {
        let marker = PathBuf::from(std::env::var("MAOBI_TEST_HOOK_MARKER").unwrap_or_default());
        let signals = SIGNALS.load(Ordering::SeqCst);
        std::fs::write(&marker, step).with_context(|| format!("MAOBI_TEST_HOOK_MARKER {}", marker.display()))?;
        let t0 = std::time::Instant::now();
        while marker.exists() && SIGNALS.load(Ordering::SeqCst) == signals && t0.elapsed().as_secs() < 60 {
            std::thread::sleep(std::time::Duration::from_millis(5));
        }
    }
    Ok(())
}

/// An exclusive claim on an output path for one run: the file `.NAME.maobi-lock` beside it,
/// created only if absent, holding the run's process id; removed when dropped or on Ctrl-C.
/// A lock whose process no longer runs is taken over with a note on stderr.
pub struct OutputLock {
    path: PathBuf,
    _remove_on_interrupt: TempGuard,
}

impl OutputLock {
    /// Takes the lock of `out` (`flag` names it in errors, e.g. `--output`).
    ///
    /// # Errors
    /// Another running maobi holds the lock (the error names its process id and the lock
    /// file), or the lock file cannot be created.
    pub fn acquire(flag: &str, out: &Path) -> Result<Self> {
        let parent = parent_of(out);
        std::fs::create_dir_all(&parent).with_context(|| format!("cannot create folder {}", parent.display()))?;
        let path = parent.join(format!(".{}.maobi-lock", name_of(out)));
        // Ctrl-C waits until the lock is registered for removal.
        let _gate = output_gate();
        for attempt in 0..5 {
            match std::fs::OpenOptions::new().write(true).create_new(true).open(&path) {
                Ok(mut f) => {
                    let guard = TempGuard::new(&path);
                    let lock = OutputLock { path: path.clone(), _remove_on_interrupt: guard };
                    f.write_all(format!("{}\n", std::process::id()).as_bytes())
                        .with_context(|| format!("cannot write the lock file {}", path.display()))?;
                    return Ok(lock);
                }
                Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => {
                    let owner = std::fs::read_to_string(&path).ok().and_then(|s| s.trim().parse::<u32>().ok());
                    match owner {
                        Some(pid) if process_alive(pid) => bail!(
                            "{flag} {}: another maobi run (process {pid}) is writing it (lock file {}); wait for it to finish",
                            out.display(),
                            path.display()
                        ),
                        // Being written by its owner right now: look again shortly.
                        None if attempt == 0 => std::thread::sleep(std::time::Duration::from_millis(100)),
                        _ => {
                            let who = owner.map_or("an unreadable process id".into(), |p| format!("process {p}"));
                            eprintln!(
                                "note: taking over the lock {} of a maobi run that no longer runs ({who})",
                                path.display()
                            );
                            match std::fs::remove_file(&path) {
                                Ok(()) => {}
                                Err(e) if e.kind() == std::io::ErrorKind::NotFound => {}
                                Err(e) => {
                                    return Err(e)
                                        .with_context(|| format!("cannot remove the stale lock {}", path.display()));
                                }
                            }
                        }
                    }
                }
                Err(e) => return Err(e).with_context(|| format!("cannot create the lock file {}", path.display())),
            }
        }
        bail!("{flag} {}: cannot take the lock {} (other runs keep taking it)", out.display(), path.display())
    }
}

impl Drop for OutputLock {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.path);
    }
}

/// Cleans up what runs that died (killed, or the machine stopped) left beside `out`: a moved-aside
/// old output `.NAME.maobi-partial-PID.old` is put back when `out` is missing (the run died in
/// the middle of its swap) and removed otherwise (it died after installing its output); a staging
/// folder `.NAME.maobi-partial-PID` is removed. Only leftovers of processes that no longer run
/// are touched, each with a note on stderr. Call it holding the [`OutputLock`].
///
/// # Errors
/// A leftover cannot be moved or removed.
pub fn recover_leftovers(out: &Path) -> Result<()> {
    let parent = parent_of(out);
    let prefix = format!(".{}.maobi-partial-", name_of(out));
    let Ok(entries) = std::fs::read_dir(&parent) else { return Ok(()) };
    let _gate = output_gate();
    let (mut olds, mut partials) = (Vec::new(), Vec::new());
    for e in entries.flatten() {
        let file = e.file_name().to_string_lossy().into_owned();
        let Some(rest) = file.strip_prefix(&prefix) else { continue };
        let (pid, old) = rest.strip_suffix(".old").map_or((rest, false), |p| (p, true));
        let Ok(pid) = pid.parse::<u32>() else { continue };
        if pid == std::process::id() || process_alive(pid) {
            continue;
        }
        if old { olds.push((pid, e.path())) } else { partials.push((pid, e.path())) }
    }
    for (pid, old) in olds {
        if std::fs::symlink_metadata(out).is_err() {
            std::fs::rename(&old, out)
                .with_context(|| format!("cannot put back {} as {}", old.display(), out.display()))?;
            eprintln!(
                "note: put back {} from {}: a maobi run (process {pid}) stopped in the middle of replacing it",
                out.display(),
                old.display()
            );
        } else {
            std::fs::remove_dir_all(&old).with_context(|| format!("cannot remove {}", old.display()))?;
            eprintln!(
                "note: removed {}, the old {} a maobi run (process {pid}) had replaced before it stopped",
                old.display(),
                out.display()
            );
        }
    }
    for (pid, p) in partials {
        std::fs::remove_dir_all(&p).with_context(|| format!("cannot remove {}", p.display()))?;
        eprintln!("note: removed {}, the unfinished output of a maobi run (process {pid}) that stopped", p.display());
    }
    Ok(())
}

/// The file in every output folder a run installs that lists, one relative path (`/`-separated)
/// a line, each file the run wrote there: what a later `--force` may replace.
pub const MANIFEST: &str = ".maobi-written";

/// Every file under `dir` (not following symlinks; a symlink counts as a file), as relative
/// `/`-separated paths, sorted.
fn files_under(dir: &Path) -> Result<Vec<String>> {
    let mut out = Vec::new();
    let mut todo = vec![(dir.to_path_buf(), String::new())];
    while let Some((d, rel)) = todo.pop() {
        for e in std::fs::read_dir(&d).with_context(|| format!("cannot read {}", d.display()))? {
            let e = e.with_context(|| format!("cannot read {}", d.display()))?;
            let name = e.file_name().to_string_lossy().into_owned();
            let r = if rel.is_empty() { name } else { format!("{rel}/{name}") };
            if e.file_type().with_context(|| format!("cannot read {}", e.path().display()))?.is_dir() {
                todo.push((e.path(), r));
            } else {
                out.push(r);
            }
        }
    }
    out.sort();
    Ok(out)
}

/// The files in the output folder `out` that no maobi run wrote: not listed in its
/// [`MANIFEST`] (all of them when it has none).
///
/// # Errors
/// The folder cannot be read.
pub fn foreign_files(out: &Path) -> Result<Vec<String>> {
    let listed: std::collections::HashSet<String> = std::fs::read_to_string(out.join(MANIFEST))
        .map(|s| s.lines().map(str::to_string).collect())
        .unwrap_or_default();
    Ok(files_under(out)?.into_iter().filter(|f| f != MANIFEST && !listed.contains(f)).collect())
}

/// The error for an output folder holding files maobi did not write.
fn foreign_error(flag: &str, out: &Path, foreign: &[String]) -> anyhow::Error {
    let shown: Vec<&str> = foreign.iter().take(5).map(String::as_str).collect();
    let more =
        if foreign.len() > shown.len() { format!(" and {} more", foreign.len() - shown.len()) } else { String::new() };
    anyhow::anyhow!(
        "{flag} {}: holds {} file(s) maobi did not write ({}{more}); --force replaces only what maobi wrote there: move them away, or name another folder",
        out.display(),
        foreign.len(),
        shown.join(", ")
    )
}

/// Refuses an existing non-empty output folder (a file, or a folder with anything in it) unless
/// `force`; with `force`, refuses anything but a folder, and a folder holding files no maobi
/// run wrote ([`foreign_files`]). `flag` names the output in errors.
///
/// # Errors
/// As described, naming the flag and the path (and the files maobi did not write).
pub fn check_output_folder(flag: &str, out: &Path, force: bool) -> Result<()> {
    let meta = match std::fs::symlink_metadata(out) {
        Ok(m) => m,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(()),
        Err(e) => bail!("{flag} {}: {e}", out.display()),
    };
    if force {
        if !meta.is_dir() {
            bail!("{flag} {}: exists and is not a folder; --force replaces folders only", out.display());
        }
        let foreign = foreign_files(out)?;
        if !foreign.is_empty() {
            return Err(foreign_error(flag, out, &foreign));
        }
        return Ok(());
    }
    if !folder_is_empty(out, &meta)? {
        bail!(
            "{flag} {}: already exists and is not empty; give --force to replace it (a run never mixes with an older one)",
            out.display()
        );
    }
    Ok(())
}

fn folder_is_empty(out: &Path, meta: &std::fs::Metadata) -> Result<bool> {
    Ok(meta.is_dir()
        && std::fs::read_dir(out).with_context(|| format!("cannot read {}", out.display()))?.next().is_none())
}

/// Refuses to replace an existing single-file output unless `force` (as every command treats an
/// existing output: never replaced silently). `flag` names the output. A symlink is followed
/// to the file it names ([`output_target`]).
///
/// # Errors
/// `path` (or the file it links to) exists and `force` is not given; as [`output_target`].
pub fn check_output_file(flag: &str, path: &Path, force: bool) -> Result<()> {
    // Through symlinks to the file that would be written; special files are refused there.
    let target = output_target(path)?;
    if !force && target.is_file() {
        bail!("{flag} {}: already exists; give --force to replace it", path.display());
    }
    Ok(())
}

/// Whether `out` is missing or an empty folder (nothing a run would replace).
pub fn output_is_vacant(out: &Path) -> bool {
    match std::fs::symlink_metadata(out) {
        Err(_) => true,
        Ok(m) => folder_is_empty(out, &m).unwrap_or(false),
    }
}

/// A staging folder `.NAME.maobi-partial-PID` beside an output folder: a run writes everything
/// there, then [`Stage::install`] swaps it in. Dropped uninstalled (an error), or on Ctrl-C, it
/// is removed.
pub struct Stage {
    path: PathBuf,
    installed: bool,
    _remove_on_interrupt: TempGuard,
}

impl Stage {
    /// Creates the staging folder of `out` (and `out`'s parent when missing).
    ///
    /// # Errors
    /// A folder cannot be created.
    pub fn new(out: &Path) -> Result<Self> {
        let parent = parent_of(out);
        std::fs::create_dir_all(&parent).with_context(|| format!("cannot create folder {}", parent.display()))?;
        let path = parent.join(format!(".{}.maobi-partial-{}", name_of(out), std::process::id()));
        // Ctrl-C waits until the folder exists and is registered for removal.
        let _gate = output_gate();
        if std::fs::symlink_metadata(&path).is_ok() {
            std::fs::remove_dir_all(&path).with_context(|| format!("cannot remove {}", path.display()))?;
        }
        let guard = TempGuard::new(&path);
        std::fs::create_dir(&path).with_context(|| format!("cannot create folder {}", path.display()))?;
        Ok(Stage { path, installed: false, _remove_on_interrupt: guard })
    }

    /// The staging folder.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Puts the staged folder in place of `out`. Without `replace`, one rename that fails if `out`
    /// is anything but missing or an empty folder (it appeared while this run worked). With
    /// `replace`, three steps: the old `out` is renamed to `.NAME.maobi-partial-PID.old`, the
    /// staged folder to `out`, and the old one is removed. An error or a signal before the last
    /// step puts the old folder back (a signal then exits 130); failing to remove the old one
    /// only warns (the next run removes it, [`recover_leftovers`]). Signals wait for the swap.
    ///
    /// # Errors
    /// A rename fails (the old output is back in place), or `out` appeared meanwhile.
    pub fn install(mut self, flag: &str, out: &Path, replace: bool) -> Result<()> {
        let gate = output_gate();
        let signals = SIGNALS.load(Ordering::SeqCst);
        let step = |name: &str| -> Result<()> {
            test_hook(name)?;
            if SIGNALS.load(Ordering::SeqCst) != signals {
                bail!("interrupted");
            }
            Ok(())
        };
        let old = parent_of(&self.path).join(format!("{}.old", name_of(&self.path)));
        let had_old = replace && std::fs::symlink_metadata(out).is_ok();
        let result = (|| -> Result<()> {
            // What this run wrote, for the next --force.
            let mut list = files_under(&self.path)?.join("\n");
            list.push('\n');
            std::fs::write(self.path.join(MANIFEST), list)
                .with_context(|| format!("cannot write {}", self.path.join(MANIFEST).display()))?;
            // A file put into the old folder while this run worked is not replaced either.
            if had_old && std::fs::symlink_metadata(out).is_ok_and(|m| m.is_dir()) {
                let foreign = foreign_files(out)?;
                if !foreign.is_empty() {
                    return Err(foreign_error(flag, out, &foreign));
                }
            }
            step("swap-aside")?;
            if had_old {
                std::fs::rename(out, &old)
                    .with_context(|| format!("cannot move the old {} aside to {}", out.display(), old.display()))?;
            }
            let restore = |e: anyhow::Error| -> anyhow::Error {
                if had_old {
                    if let Err(r) = std::fs::rename(&old, out) {
                        return e.context(format!(
                            "and cannot put the old {} back from {} ({r}); rename it back by hand",
                            out.display(),
                            old.display()
                        ));
                    }
                }
                e
            };
            step("swap-install").map_err(restore)?;
            if let Err(e) = std::fs::rename(&self.path, out) {
                let appeared = !replace && std::fs::symlink_metadata(out).is_ok();
                let e = if appeared {
                    anyhow::anyhow!(
                        "{flag} {}: appeared while this run was working and is not empty; nothing was replaced (give --force to replace it)",
                        out.display()
                    )
                } else {
                    anyhow::Error::from(e).context(format!("cannot move the new outputs to {}", out.display()))
                };
                return Err(restore(e));
            }
            if let Err(e) = step("swap-cleanup") {
                // Back to the state before the swap: the new folder to staging, the old in place.
                return match std::fs::rename(out, &self.path) {
                    Ok(()) => Err(restore(e)),
                    Err(r) => Err(e.context(format!("and cannot take the new {} out again ({r})", out.display()))),
                };
            }
            self.installed = true;
            if had_old {
                if let Err(e) = std::fs::remove_dir_all(&old) {
                    eprintln!(
                        "warning: cannot remove the old outputs {}: {e} (the next run removes them)",
                        old.display()
                    );
                }
            }
            Ok(())
        })();
        drop(gate);
        if result.is_err() && SIGNALS.load(Ordering::SeqCst) != signals {
            exit_interrupted();
        }
        result
    }
}

impl Drop for Stage {
    fn drop(&mut self) {
        if !self.installed {
            let _ = std::fs::remove_dir_all(&self.path);
        }
    }
}

/// `p` made absolute without following what does not exist yet: the longest existing ancestor
/// canonicalised (symlinks resolved), the rest appended with `.` and `..` folded.
fn resolved(p: &Path) -> PathBuf {
    let abs = if p.is_absolute() {
        p.to_path_buf()
    } else {
        std::env::current_dir().map_or_else(|_| p.to_path_buf(), |d| d.join(p))
    };
    let mut base = abs.clone();
    let mut rest = Vec::new();
    loop {
        if let Ok(c) = std::fs::canonicalize(&base) {
            base = c;
            break;
        }
        match (base.file_name().map(|n| n.to_os_string()), base.parent().map(Path::to_path_buf)) {
            (Some(n), Some(parent)) => {
                rest.push(n);
                base = parent;
            }
            _ => break,
        }
    }
    for n in rest.into_iter().rev() {
        match n.to_str() {
            Some(".") => {}
            Some("..") => {
                base.pop();
            }
            _ => base.push(n),
        }
    }
    base
}

/// Refuses an output folder or file that is one of the run's inputs, lies inside one, or
/// holds one (replacing it would delete what the run reads). `inputs` pairs each input's flag
/// with its path; paths are compared after resolving symlinks.
///
/// # Errors
/// Naming both flags and paths.
pub fn check_output_apart(out_flag: &str, out: &Path, inputs: &[(&str, &Path)]) -> Result<()> {
    let o = resolved(out);
    for (flag, input) in inputs {
        let i = resolved(input);
        let how = if o == i {
            "is"
        } else if o.starts_with(&i) {
            "lies inside"
        } else if i.starts_with(&o) {
            "holds"
        } else {
            continue;
        };
        bail!(
            "{out_flag} {}: {how} the input {flag} {} (writing there would replace what this run reads): name another output",
            out.display(),
            input.display()
        );
    }
    Ok(())
}

/// Writes `bytes` to `root/rel` ([`write_atomic`]) after checking that `rel` is a relative path
/// of plain names (no `..`, no root, no prefix), so that the file stays under `root`.
///
/// # Errors
/// A `rel` that could leave `root`; as [`write_atomic`].
pub fn write_under(root: &Path, rel: &Path, bytes: &[u8]) -> Result<()> {
    use std::path::Component;
    if rel.as_os_str().is_empty() || !rel.components().all(|c| matches!(c, Component::Normal(_))) {
        bail!("refusing to write {} outside the output folder {}", rel.display(), root.display());
    }
    write_atomic(&root.join(rel), bytes)
}
