//! Output folders: a lock per output, a staging folder swapped in at the end, the leftovers of
//! runs that died on the way, the files a run may replace, and outputs kept apart from inputs.
//! The layout on disk is in the crate's README.

use std::io::Write;
use std::path::{Path, PathBuf};

use crate::interrupt::{TempGuard, output_gate, signal_count, test_hook};
use crate::{Error, Names, Notice, Overlap};

/// The folder that holds `out` (`.` for a bare name).
pub(crate) fn parent_of(out: &Path) -> PathBuf {
    match out.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    }
}

/// The last component of `out`, for the hidden names beside it.
pub(crate) fn name_of(out: &Path) -> String {
    out.file_name().map_or("out".into(), |n| n.to_string_lossy().into_owned())
}

/// Whether process `pid` still runs. Only Linux can tell (`/proc`); elsewhere every process is
/// taken to run, so nothing another run left is ever removed.
fn process_alive(pid: u32) -> bool {
    if cfg!(target_os = "linux") { Path::new("/proc").join(pid.to_string()).exists() } else { true }
}

/// An exclusive claim on an output path for one run: the file `.NAME.maobi-lock` beside it,
/// created only if absent, holding the run's process id; removed when dropped, or by
/// [`crate::remove_temporaries`] after a signal.
#[derive(Debug)]
pub struct OutputLock {
    path: PathBuf,
    _remove_on_interrupt: TempGuard,
}

impl OutputLock {
    /// Takes the lock of `out` (`label` names it in errors). A lock whose process no longer
    /// runs is taken over, with a [`Notice::LockTakenOver`] to `notes`. Creates `out`'s parent
    /// folder when missing.
    ///
    /// # Errors
    /// [`Error::Locked`] when another running process holds it (naming its process id and the
    /// lock file), [`Error::LockContended`] when other runs keep taking it, [`Error::Io`] when
    /// the lock file or the folder cannot be created.
    ///
    /// # Examples
    /// ```
    /// use safe_output::OutputLock;
    /// let out = std::env::temp_dir().join(format!("safe-output-doc-lock-{}", std::process::id()));
    /// let lock = OutputLock::acquire("out", &out, &mut |n| eprintln!("note: {n}")).unwrap();
    /// // A second claim while this process holds it fails.
    /// assert!(OutputLock::acquire("out", &out, &mut |_| {}).is_err());
    /// drop(lock);
    /// OutputLock::acquire("out", &out, &mut |_| {}).unwrap();
    /// ```
    pub fn acquire(label: &str, out: &Path, notes: &mut dyn FnMut(Notice)) -> Result<Self, Error> {
        let parent = parent_of(out);
        std::fs::create_dir_all(&parent).map_err(Error::io("cannot create folder", &parent))?;
        let path = parent.join(format!(".{}.maobi-lock", name_of(out)));
        // A signal's clean-up waits until the lock is registered for removal.
        let _gate = output_gate();
        for attempt in 0..5 {
            match std::fs::OpenOptions::new().write(true).create_new(true).open(&path) {
                Ok(mut f) => {
                    let guard = TempGuard::new(&path);
                    let lock = OutputLock { path: path.clone(), _remove_on_interrupt: guard };
                    f.write_all(format!("{}\n", std::process::id()).as_bytes())
                        .map_err(Error::io("cannot write the lock file", &path))?;
                    return Ok(lock);
                }
                Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => {
                    let owner = std::fs::read_to_string(&path).ok().and_then(|s| s.trim().parse::<u32>().ok());
                    match owner {
                        Some(pid) if process_alive(pid) => {
                            return Err(Error::Locked { label: label.into(), out: out.to_path_buf(), pid, lock: path });
                        }
                        // Being written by its owner right now: look again shortly.
                        None if attempt == 0 => std::thread::sleep(std::time::Duration::from_millis(100)),
                        _ => {
                            notes(Notice::LockTakenOver { lock: path.clone(), pid: owner });
                            match std::fs::remove_file(&path) {
                                Ok(()) => {}
                                Err(e) if e.kind() == std::io::ErrorKind::NotFound => {}
                                Err(e) => return Err(Error::io("cannot remove the stale lock", &path)(e)),
                            }
                        }
                    }
                }
                Err(e) => return Err(Error::io("cannot create the lock file", &path)(e)),
            }
        }
        Err(Error::LockContended { label: label.into(), out: out.to_path_buf(), lock: path })
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
/// folder `.NAME.maobi-partial-PID` (or a [`crate::FileSet`]'s file of that name) is removed. Only leftovers of processes that no longer run
/// are touched, each reported to `notes`. Call it holding the [`OutputLock`].
///
/// # Errors
/// [`Error::PutBack`] or [`Error::Io`] when a leftover cannot be moved or removed.
///
/// # Examples
/// ```
/// let out = std::env::temp_dir().join(format!("safe-output-doc-recover-{}", std::process::id()));
/// let mut notes = Vec::new();
/// safe_output::recover_leftovers(&out, &mut |n| notes.push(n.to_string())).unwrap();
/// assert!(notes.is_empty(), "nothing was left beside a fresh output");
/// ```
pub fn recover_leftovers(out: &Path, notes: &mut dyn FnMut(Notice)) -> Result<(), Error> {
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
            std::fs::rename(&old, out).map_err(|source| Error::PutBack {
                old: old.clone(),
                out: out.to_path_buf(),
                source,
            })?;
            notes(Notice::PutBack { out: out.to_path_buf(), old, pid });
        } else {
            std::fs::remove_dir_all(&old).map_err(Error::io("cannot remove", &old))?;
            notes(Notice::RemovedOld { old, out: out.to_path_buf(), pid });
        }
    }
    for (pid, p) in partials {
        // A staging folder, or a file a [`crate::FileSet`] was writing.
        let file = std::fs::symlink_metadata(&p).is_ok_and(|m| !m.is_dir());
        if file { std::fs::remove_file(&p) } else { std::fs::remove_dir_all(&p) }
            .map_err(Error::io("cannot remove", &p))?;
        notes(Notice::RemovedPartial { partial: p, pid });
    }
    Ok(())
}

/// The file in every output folder a [`Stage`] installs that lists, one relative path
/// (`/`-separated) a line, each file the run wrote there: what a later forced run may replace.
pub const MANIFEST: &str = ".maobi-written";

/// Every file under `dir` (not following symlinks; a symlink counts as a file), as relative
/// `/`-separated paths, sorted.
fn files_under(dir: &Path) -> Result<Vec<String>, Error> {
    let mut out = Vec::new();
    let mut todo = vec![(dir.to_path_buf(), String::new())];
    while let Some((d, rel)) = todo.pop() {
        for e in std::fs::read_dir(&d).map_err(Error::io("cannot read", &d))? {
            let e = e.map_err(Error::io("cannot read", &d))?;
            let name = e.file_name().to_string_lossy().into_owned();
            let r = if rel.is_empty() { name } else { format!("{rel}/{name}") };
            if e.file_type().map_err(Error::io("cannot read", e.path()))?.is_dir() {
                todo.push((e.path(), r));
            } else {
                out.push(r);
            }
        }
    }
    out.sort();
    Ok(out)
}

/// The files in the output folder `out` that no run wrote: not listed in its [`MANIFEST`]
/// (all of them when it has none), as relative `/`-separated paths, sorted.
///
/// # Errors
/// [`Error::Io`] when the folder cannot be read.
pub fn foreign_files(out: &Path) -> Result<Vec<String>, Error> {
    let listed: std::collections::HashSet<String> = std::fs::read_to_string(out.join(MANIFEST))
        .map(|s| s.lines().map(str::to_string).collect())
        .unwrap_or_default();
    Ok(files_under(out)?.into_iter().filter(|f| f != MANIFEST && !listed.contains(f)).collect())
}

/// [`Error::Foreign`] for `out` when it holds `foreign` files.
fn foreign_error(names: Names<'_>, out: &Path, foreign: Vec<String>) -> Error {
    Error::Foreign { label: names.output.into(), replace: names.replace.into(), out: out.to_path_buf(), files: foreign }
}

/// Refuses an existing non-empty output folder (a file, or a folder with anything in it) unless
/// `force`; with `force`, refuses anything but a folder, and a folder holding files no run
/// wrote ([`foreign_files`]).
///
/// # Errors
/// [`Error::NotEmpty`], [`Error::NotAFolder`], [`Error::Foreign`], naming the output and the
/// option as `names` says; [`Error::Inspect`] or [`Error::Io`] when `out` cannot be read.
///
/// # Examples
/// ```
/// use safe_output::{Names, check_output_folder};
/// let names = Names { output: "out", replace: "overwrite=True" };
/// let out = std::env::temp_dir().join(format!("safe-output-doc-folder-{}", std::process::id()));
/// check_output_folder(names, &out, false).unwrap(); // missing
/// std::fs::create_dir_all(&out).unwrap();
/// std::fs::write(out.join("mine.txt"), "not written by a run").unwrap();
/// assert!(check_output_folder(names, &out, false).is_err()); // not empty
/// assert!(check_output_folder(names, &out, true).is_err()); // holds a foreign file
/// # std::fs::remove_dir_all(&out).unwrap();
/// ```
pub fn check_output_folder(names: Names<'_>, out: &Path, force: bool) -> Result<(), Error> {
    let meta = match std::fs::symlink_metadata(out) {
        Ok(m) => m,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(()),
        Err(source) => return Err(Error::Inspect { label: names.output.into(), path: out.to_path_buf(), source }),
    };
    if force {
        if !meta.is_dir() {
            return Err(Error::NotAFolder {
                label: names.output.into(),
                replace: names.replace.into(),
                out: out.to_path_buf(),
            });
        }
        let foreign = foreign_files(out)?;
        if !foreign.is_empty() {
            return Err(foreign_error(names, out, foreign));
        }
        return Ok(());
    }
    if !folder_is_empty(out, &meta)? {
        return Err(Error::NotEmpty {
            label: names.output.into(),
            replace: names.replace.into(),
            out: out.to_path_buf(),
        });
    }
    Ok(())
}

fn folder_is_empty(out: &Path, meta: &std::fs::Metadata) -> Result<bool, Error> {
    Ok(meta.is_dir() && std::fs::read_dir(out).map_err(Error::io("cannot read", out))?.next().is_none())
}

/// Whether `out` is missing or an empty folder (nothing a run would replace).
pub fn output_is_vacant(out: &Path) -> bool {
    match std::fs::symlink_metadata(out) {
        Err(_) => true,
        Ok(m) => folder_is_empty(out, &m).unwrap_or(false),
    }
}

/// A staging folder `.NAME.maobi-partial-PID` beside an output folder: a run writes everything
/// there, then [`Stage::install`] swaps it in. Dropped uninstalled (an error), or removed by
/// [`crate::remove_temporaries`] after a signal.
#[derive(Debug)]
pub struct Stage {
    path: PathBuf,
    installed: bool,
    _remove_on_interrupt: TempGuard,
}

impl Stage {
    /// Creates the staging folder of `out` (and `out`'s parent when missing), empty.
    ///
    /// # Errors
    /// [`Error::Io`] when a folder cannot be created (or an old one of this process removed).
    ///
    /// # Examples
    /// ```
    /// use safe_output::{Names, Stage};
    /// let out = std::env::temp_dir().join(format!("safe-output-doc-stage-{}", std::process::id()));
    /// let stage = Stage::new(&out).unwrap();
    /// safe_output::write_atomic(&stage.path().join("a.txt"), b"a").unwrap();
    /// let names = Names { output: "out", replace: "overwrite=True" };
    /// stage.install(names, &out, false, &mut |_| {}).unwrap();
    /// assert_eq!(std::fs::read(out.join("a.txt")).unwrap(), b"a");
    /// # std::fs::remove_dir_all(&out).unwrap();
    /// ```
    pub fn new(out: &Path) -> Result<Self, Error> {
        let parent = parent_of(out);
        std::fs::create_dir_all(&parent).map_err(Error::io("cannot create folder", &parent))?;
        let path = parent.join(format!(".{}.maobi-partial-{}", name_of(out), std::process::id()));
        // A signal's clean-up waits until the folder exists and is registered for removal.
        let _gate = output_gate();
        if std::fs::symlink_metadata(&path).is_ok() {
            std::fs::remove_dir_all(&path).map_err(Error::io("cannot remove", &path))?;
        }
        let guard = TempGuard::new(&path);
        std::fs::create_dir(&path).map_err(Error::io("cannot create folder", &path))?;
        Ok(Stage { path, installed: false, _remove_on_interrupt: guard })
    }

    /// The staging folder.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Puts the staged folder in place of `out`, first listing what it holds in its
    /// [`MANIFEST`]. Without `replace`, one rename that fails if `out` is anything but missing
    /// or an empty folder (it appeared while this run worked). With `replace`, three steps: the
    /// old `out` is renamed to `.NAME.maobi-partial-PID.old`, the staged folder to `out`, and the
    /// old one is removed. An error, or a signal ([`crate::record_signal`]) before the last step,
    /// puts the old folder back; failing to remove the old one is only a
    /// [`Notice::OldNotRemoved`] (the next run removes it, [`recover_leftovers`]). The swap
    /// holds the [`crate::output_gate`]; [`crate::test_hook`] runs before each step.
    ///
    /// # Errors
    /// [`Error::Interrupted`] (a signal came), [`Error::Appeared`], [`Error::Foreign`] (files
    /// put into the old folder meanwhile), [`Error::MoveAside`] or [`Error::Io`] when a rename
    /// fails: the old output is back in place, or [`Error::NotRestored`] says where it lies.
    pub fn install(
        mut self,
        names: Names<'_>,
        out: &Path,
        replace: bool,
        notes: &mut dyn FnMut(Notice),
    ) -> Result<(), Error> {
        let _gate = output_gate();
        let signals = signal_count();
        let step = |name: &str| -> Result<(), Error> {
            test_hook(name)?;
            if signal_count() != signals {
                return Err(Error::Interrupted);
            }
            Ok(())
        };
        let old = parent_of(&self.path).join(format!("{}.old", name_of(&self.path)));
        let had_old = replace && std::fs::symlink_metadata(out).is_ok();
        // What this run wrote, for the next forced run.
        let mut list = files_under(&self.path)?.join("\n");
        list.push('\n');
        std::fs::write(self.path.join(MANIFEST), list).map_err(Error::io("cannot write", self.path.join(MANIFEST)))?;
        // A file put into the old folder while this run worked is not replaced either.
        if had_old && std::fs::symlink_metadata(out).is_ok_and(|m| m.is_dir()) {
            let foreign = foreign_files(out)?;
            if !foreign.is_empty() {
                return Err(foreign_error(names, out, foreign));
            }
        }
        step("swap-aside")?;
        if had_old {
            std::fs::rename(out, &old).map_err(|source| Error::MoveAside {
                out: out.to_path_buf(),
                old: old.clone(),
                source,
            })?;
        }
        let restore = |e: Error| -> Error {
            if had_old {
                if let Err(restore) = std::fs::rename(&old, out) {
                    return Error::NotRestored {
                        out: out.to_path_buf(),
                        old: old.clone(),
                        restore,
                        source: Box::new(e),
                    };
                }
            }
            e
        };
        step("swap-install").map_err(restore)?;
        if let Err(e) = std::fs::rename(&self.path, out) {
            let appeared = !replace && std::fs::symlink_metadata(out).is_ok();
            let e = if appeared {
                Error::Appeared { label: names.output.into(), replace: names.replace.into(), out: out.to_path_buf() }
            } else {
                Error::io("cannot move the new outputs to", out)(e)
            };
            return Err(restore(e));
        }
        if let Err(e) = step("swap-cleanup") {
            // Back to the state before the swap: the new folder to staging, the old in place.
            return match std::fs::rename(out, &self.path) {
                Ok(()) => Err(restore(e)),
                Err(restore) => Err(Error::NotTakenOut { out: out.to_path_buf(), restore, source: Box::new(e) }),
            };
        }
        self.installed = true;
        if had_old {
            if let Err(source) = std::fs::remove_dir_all(&old) {
                notes(Notice::OldNotRemoved { old, source });
            }
        }
        Ok(())
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
/// holds one (replacing it would delete what the run reads). `inputs` pairs each input's name
/// with its path; paths are compared after resolving symlinks.
///
/// # Errors
/// [`Error::Overlaps`], naming both outputs and paths.
///
/// # Examples
/// ```
/// use std::path::Path;
/// let e = safe_output::check_output_apart("out", Path::new("photos/out"), &[("photos", Path::new("photos"))])
///     .unwrap_err();
/// assert!(e.to_string().starts_with("out photos/out: lies inside the input photos photos"));
/// safe_output::check_output_apart("out", Path::new("results"), &[("photos", Path::new("photos"))]).unwrap();
/// ```
pub fn check_output_apart(label: &str, out: &Path, inputs: &[(&str, &Path)]) -> Result<(), Error> {
    let o = resolved(out);
    for (input_label, input) in inputs {
        let i = resolved(input);
        let how = if o == i {
            Overlap::Is
        } else if o.starts_with(&i) {
            Overlap::LiesInside
        } else if i.starts_with(&o) {
            Overlap::Holds
        } else {
            continue;
        };
        return Err(Error::Overlaps {
            label: label.into(),
            out: out.to_path_buf(),
            how,
            input_label: (*input_label).into(),
            input: input.to_path_buf(),
        });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tests::names;

    /// A process id that runs nowhere (Linux's largest is 2^22).
    const DEAD: u32 = 4_000_000_000;

    fn scratch(name: &str) -> PathBuf {
        crate::tests::scratch(&format!("folder-{name}"))
    }

    const NAMES: Names<'static> = Names { output: "out", replace: "overwrite" };

    #[test]
    fn a_lock_is_exclusive_and_a_dead_runs_lock_is_taken_over() {
        let d = scratch("lock");
        let out = d.join("o");
        let lock = OutputLock::acquire("out", &out, &mut |_| panic!("no notice")).unwrap();
        assert_eq!(std::fs::read_to_string(d.join(".o.maobi-lock")).unwrap(), format!("{}\n", std::process::id()));
        let e = OutputLock::acquire("out", &out, &mut |_| {}).unwrap_err();
        assert!(matches!(e, Error::Locked { pid, .. } if pid == std::process::id()), "{e}");
        drop(lock);
        assert_eq!(names(&d), Vec::<String>::new());
        if cfg!(target_os = "linux") {
            std::fs::write(d.join(".o.maobi-lock"), format!("{DEAD}\n")).unwrap();
            let mut notes = Vec::new();
            let _lock = OutputLock::acquire("out", &out, &mut |n| notes.push(n.to_string())).unwrap();
            assert_eq!(notes.len(), 1);
            assert!(notes[0].starts_with("taking over the lock") && notes[0].ends_with(&format!("(process {DEAD})")));
        }
        std::fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn a_dead_runs_leftovers_are_put_back_or_removed() {
        if !cfg!(target_os = "linux") {
            return;
        }
        let d = scratch("recover");
        let out = d.join("o");
        // Died in the middle of a swap: the old output lies aside, `o` is missing.
        std::fs::create_dir_all(d.join(format!(".o.maobi-partial-{DEAD}.old"))).unwrap();
        std::fs::write(d.join(format!(".o.maobi-partial-{DEAD}.old/a")), "old").unwrap();
        std::fs::create_dir_all(d.join(format!(".o.maobi-partial-{}", DEAD + 1))).unwrap();
        // Another output's leftovers are not touched.
        std::fs::create_dir_all(d.join(format!(".other.maobi-partial-{DEAD}"))).unwrap();
        let mut notes = Vec::new();
        recover_leftovers(&out, &mut |n| notes.push(n)).unwrap();
        assert_eq!(std::fs::read_to_string(out.join("a")).unwrap(), "old");
        assert_eq!(names(&d), [format!(".other.maobi-partial-{DEAD}"), "o".into()]);
        assert!(matches!(notes[..], [Notice::PutBack { .. }, Notice::RemovedPartial { .. }]), "{notes:?}");
        // Died after installing: the old one is removed, the new one stays.
        std::fs::create_dir_all(d.join(format!(".o.maobi-partial-{DEAD}.old"))).unwrap();
        recover_leftovers(&out, &mut |_| {}).unwrap();
        assert!(out.join("a").exists() && !d.join(format!(".o.maobi-partial-{DEAD}.old")).exists());
        // A file a dead run's `FileSet` was writing beside a single-file output goes too.
        std::fs::write(d.join(format!(".f.txt.maobi-partial-{DEAD}")), "half").unwrap();
        std::fs::write(d.join("f.txt"), "whole").unwrap();
        recover_leftovers(&d.join("f.txt"), &mut |_| {}).unwrap();
        assert_eq!(names(&d), [format!(".other.maobi-partial-{DEAD}"), "f.txt".into(), "o".into()]);
        std::fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn an_install_lists_what_it_wrote_and_a_forced_one_replaces_only_that() {
        let d = scratch("install");
        let out = d.join("o");
        let stage = Stage::new(&out).unwrap();
        crate::write_atomic(&stage.path().join("x/y.txt"), b"1").unwrap();
        crate::write_atomic(&stage.path().join("z.txt"), b"1").unwrap();
        stage.install(NAMES, &out, false, &mut |_| {}).unwrap();
        assert_eq!(std::fs::read_to_string(out.join(MANIFEST)).unwrap(), "x/y.txt\nz.txt\n");
        assert!(foreign_files(&out).unwrap().is_empty());
        assert!(!output_is_vacant(&out));
        // Not forced: refused; forced: replaced, and nothing is left beside it.
        let e = check_output_folder(NAMES, &out, false).unwrap_err();
        assert!(matches!(e, Error::NotEmpty { .. }), "{e}");
        check_output_folder(NAMES, &out, true).unwrap();
        let stage = Stage::new(&out).unwrap();
        crate::write_atomic(&stage.path().join("new.txt"), b"2").unwrap();
        stage.install(NAMES, &out, true, &mut |_| panic!("no notice")).unwrap();
        assert_eq!(names(&out), [MANIFEST, "new.txt"]);
        assert_eq!(names(&d), ["o"]);
        // A file no run wrote makes a forced run refuse, naming it.
        std::fs::write(out.join("mine.txt"), "mine").unwrap();
        assert_eq!(foreign_files(&out).unwrap(), ["mine.txt"]);
        let e = check_output_folder(NAMES, &out, true).unwrap_err();
        assert_eq!(
            e.to_string(),
            format!(
                "out {}: holds 1 file(s) maobi did not write (mine.txt); overwrite replaces only what maobi wrote there: move them away, or name another folder",
                out.display()
            )
        );
        // As does the install, when the file came while the run worked.
        let stage = Stage::new(&out).unwrap();
        let e = stage.install(NAMES, &out, true, &mut |_| {}).unwrap_err();
        assert!(matches!(e, Error::Foreign { .. }), "{e}");
        assert_eq!(names(&out), [MANIFEST, "mine.txt", "new.txt"]);
        assert_eq!(names(&d), ["o"], "the staging folder is removed when dropped");
        std::fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn an_output_that_appeared_meanwhile_is_not_replaced() {
        let d = scratch("appeared");
        let out = d.join("o");
        let stage = Stage::new(&out).unwrap();
        crate::write_atomic(&stage.path().join("a.txt"), b"1").unwrap();
        std::fs::create_dir(&out).unwrap();
        std::fs::write(out.join("b.txt"), "b").unwrap();
        let e = stage.install(NAMES, &out, false, &mut |_| {}).unwrap_err();
        assert!(matches!(e, Error::Appeared { .. }), "{e}");
        assert_eq!(names(&out), ["b.txt"]);
        assert_eq!(names(&d), ["o"]);
        // A file is not a folder to replace.
        std::fs::remove_dir_all(&out).unwrap();
        std::fs::write(&out, "f").unwrap();
        let e = check_output_folder(NAMES, &out, true).unwrap_err();
        assert_eq!(
            e.to_string(),
            format!("out {}: exists and is not a folder; overwrite replaces folders only", out.display())
        );
        std::fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn outputs_overlapping_inputs_are_refused_through_symlinks_and_dots() {
        let d = scratch("apart");
        std::fs::create_dir(d.join("in")).unwrap();
        let input = d.join("in");
        for (out, how) in
            [(d.join("in"), Overlap::Is), (d.join("in/x/../y"), Overlap::LiesInside), (d.clone(), Overlap::Holds)]
        {
            match check_output_apart("out", &out, &[("input", &input)]) {
                Err(Error::Overlaps { how: h, .. }) => assert_eq!(h, how, "{}", out.display()),
                r => panic!("{}: {r:?}", out.display()),
            }
        }
        check_output_apart("out", &d.join("in2"), &[("input", &input)]).unwrap();
        check_output_apart("out", &d.join("in/../out"), &[("input", &input)]).unwrap();
        #[cfg(unix)]
        {
            std::os::unix::fs::symlink("in", d.join("link")).unwrap();
            assert!(check_output_apart("out", &d.join("link/new"), &[("input", &input)]).is_err());
        }
        std::fs::remove_dir_all(&d).unwrap();
    }
}
