//! Helpers shared by the subcommands: brush selection, atomic file output, output folders
//! (staging, lock, interrupt-safe swap), stdout that ends quietly when the reader goes away,
//! Ctrl-C clean-up, and numeric flag ranges.

use std::cell::Cell;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Mutex, RwLock, RwLockReadGuard};

use anyhow::{Context, Result, bail};
use brush_model::BrushProfile;

/// The smallest image scale a flag may ask for, px per mm (a 25-dpi scan is 1 px/mm).
pub const MIN_PX_PER_MM: f64 = 0.1;
/// The largest image scale a flag may ask for, px per mm (a 250 000-dpi microscope).
pub const MAX_PX_PER_MM: f64 = 10_000.0;

/// Checks a numeric flag against a closed range (NaN is outside every range); the error names
/// the flag, the value and the range with its unit.
pub fn check_range<T: PartialOrd + std::fmt::Display + Copy>(flag: &str, v: T, lo: T, hi: T, unit: &str) -> Result<T> {
    if lo <= v && v <= hi {
        Ok(v)
    } else {
        let unit = if unit.is_empty() { String::new() } else { format!(" {unit}") };
        bail!("{flag} {}: expected {lo}..={hi}{unit}", short_number(&v.to_string()))
    }
}

/// A number as typed, or in exponent form when that is long (`1e300`, not 301 digits).
pub fn short_number(s: &str) -> String {
    match s.parse::<f64>() {
        Ok(v) if s.len() > 16 => format!("{v:e}"),
        _ => s.to_string(),
    }
}

/// Writes one line to stdout. A reader that went away (`maobi … | head`) is an error that
/// [`is_broken_pipe`] recognises, so `main` ends quietly instead of panicking as `println!` does.
#[macro_export]
macro_rules! outln {
    ($($t:tt)*) => { $crate::common::out_fmt(format_args!("{}\n", format_args!($($t)*))) };
}

/// Writes to stdout without a newline; see [`outln!`].
#[macro_export]
macro_rules! out {
    ($($t:tt)*) => { $crate::common::out_fmt(format_args!($($t)*)) };
}

/// The writer behind [`outln!`] and [`out!`].
pub fn out_fmt(args: std::fmt::Arguments<'_>) -> Result<()> {
    let mut o = std::io::stdout().lock();
    o.write_fmt(args).and_then(|()| o.flush()).map_err(anyhow::Error::from)
}

/// Whether an error (anywhere in its chain) is a write to a closed pipe.
pub fn is_broken_pipe(e: &anyhow::Error) -> bool {
    e.chain().any(|c| c.downcast_ref::<std::io::Error>().is_some_and(|io| io.kind() == std::io::ErrorKind::BrokenPipe))
}

/// Temporary files being written now: removed by the Ctrl-C handler.
static TEMPS: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());
/// Set once Ctrl-C (SIGINT) or SIGTERM arrived.
static INTERRUPTED: AtomicBool = AtomicBool::new(false);
/// Set by commands that stop by themselves at a consistent point when [`interrupted`] says so.
static COOPERATIVE: AtomicBool = AtomicBool::new(false);
static SIGNALS: AtomicUsize = AtomicUsize::new(0);

/// Removes every registered temporary file.
fn remove_temps() {
    let temps = TEMPS.lock().unwrap_or_else(|e| e.into_inner());
    for t in temps.iter() {
        // A staging folder (`maobi write`) or a temporary file.
        if t.is_dir() {
            let _ = std::fs::remove_dir_all(t);
        } else {
            let _ = std::fs::remove_file(t);
        }
    }
}

/// Installs the Ctrl-C / SIGTERM handler of every command but `robot` (which has its own):
/// temporary files are removed and the process exits with status 130 saying `interrupted`.
/// A command that called [`stop_on_interrupt`] is asked to stop instead (a second signal still
/// exits at once).
pub fn install_interrupt_handler() -> Result<()> {
    ctrlc::set_handler(|| {
        INTERRUPTED.store(true, Ordering::SeqCst);
        let n = SIGNALS.fetch_add(1, Ordering::SeqCst);
        if COOPERATIVE.load(Ordering::SeqCst) && n == 0 {
            return;
        }
        exit_interrupted();
    })
    .context("cannot install the Ctrl-C handler")
}

/// Held (shared) by every write into an output or staging folder and across a whole folder
/// swap; [`exit_interrupted`] takes it exclusively, so the clean-up never races a write (which
/// could re-create a folder just removed) and never cuts a swap in half.
static GATE: RwLock<()> = RwLock::new(());

thread_local! {
    /// How many [`GateGuard`]s this thread holds (only the first one locks).
    static GATE_DEPTH: Cell<usize> = const { Cell::new(0) };
}

/// A shared hold on the output gate; see [`output_gate`].
pub struct GateGuard {
    _guard: Option<RwLockReadGuard<'static, ()>>,
}

impl Drop for GateGuard {
    fn drop(&mut self) {
        GATE_DEPTH.with(|d| d.set(d.get().saturating_sub(1)));
    }
}

/// Holds off the Ctrl-C clean-up while a step that writes outputs runs (re-entrant within a
/// thread): a signal arriving meanwhile is acted on once the guard is dropped.
pub fn output_gate() -> GateGuard {
    let depth = GATE_DEPTH.with(|d| {
        let v = d.get();
        d.set(v + 1);
        v
    });
    GateGuard { _guard: (depth == 0).then(|| GATE.read().unwrap_or_else(|e| e.into_inner())) }
}

/// Removes the registered temporaries and exits with status 130 saying `interrupted`: once
/// every write or swap in flight has finished (waiting at most 10 s for them), and only once
/// per process (a second caller waits here until the process is gone).
pub fn exit_interrupted() -> ! {
    // A helper thread waits for the gate (writers go first: no new write starts once it waits)
    // and keeps it until the process is gone; this one waits for that at most 10 s.
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        let _gate = GATE.write().unwrap_or_else(|e| e.into_inner());
        let _ = tx.send(());
        loop {
            std::thread::park();
        }
    });
    let _ = rx.recv_timeout(std::time::Duration::from_secs(10));
    static EXITING: Mutex<()> = Mutex::new(());
    let _once = EXITING.lock().unwrap_or_else(|e| e.into_inner());
    remove_temps();
    eprintln!("error: interrupted");
    std::process::exit(130);
}

/// Asks the Ctrl-C handler to let this command stop by itself: it polls [`interrupted`].
pub fn stop_on_interrupt() {
    COOPERATIVE.store(true, Ordering::SeqCst);
}

/// How many times Ctrl-C (or SIGTERM) arrived so far: a step compares it before and after to
/// tell whether a signal came meanwhile.
pub fn signal_count() -> usize {
    SIGNALS.load(Ordering::SeqCst)
}

/// Whether Ctrl-C (or SIGTERM) arrived.
pub fn interrupted() -> bool {
    INTERRUPTED.load(Ordering::SeqCst)
}

/// Puts a temporary file that a library writes (and renames) on the list the Ctrl-C handler
/// removes, for the rest of the run.
pub fn remove_on_interrupt(p: &Path) {
    TEMPS.lock().unwrap_or_else(|e| e.into_inner()).push(p.to_path_buf());
}

/// Keeps a temporary file on the list the Ctrl-C handler removes, while it lives.
pub struct TempGuard(PathBuf);

impl TempGuard {
    /// Registers `p` (a file or a folder) for removal by the Ctrl-C handler until dropped.
    pub fn new(p: &Path) -> Self {
        TEMPS.lock().unwrap_or_else(|e| e.into_inner()).push(p.to_path_buf());
        TempGuard(p.to_path_buf())
    }
}

impl Drop for TempGuard {
    fn drop(&mut self) {
        let mut t = TEMPS.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(i) = t.iter().position(|p| *p == self.0) {
            t.swap_remove(i);
        }
    }
}

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

/// Resolves `--brush`: a built-in name (`pen1`, `pen2`) or a profile JSON file.
pub fn load_brush(spec: &str) -> Result<BrushProfile> {
    if BrushProfile::BUILTINS.contains(&spec) {
        return Ok(BrushProfile::builtin(spec)?);
    }
    let path = Path::new(spec);
    if !path.exists() && !spec.ends_with(".json") {
        anyhow::bail!("--brush `{spec}`: not a built-in brush (pen1, pen2) nor an existing profile file");
    }
    Ok(BrushProfile::load(path)?)
}

/// Writes `bytes` to `path` atomically: into a temporary file in the same folder, then renamed,
/// so a failure never leaves a half-written output. Creates the parent folder if needed. A
/// symlink is written through (its target is replaced, the link stays); folders, FIFOs, sockets
/// and devices are refused ([`output_target`]). Ctrl-C removes the temporary file.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
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
    tmp.write_all(bytes).with_context(|| format!("cannot write {}", path.display()))?;
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        // Temporary files are created private; outputs get the usual permissions.
        let _ = tmp.as_file().set_permissions(std::fs::Permissions::from_mode(0o644));
    }
    tmp.persist(path).with_context(|| format!("cannot write {}", path.display()))?;
    Ok(())
}

/// `profile.predict` for a command with `--extrapolate`: outside the calibrated range the error
/// names the flag (`hint`: what to say, e.g. "give --extrapolate to use it anyway").
pub fn predict_or_hint(
    profile: &BrushProfile,
    press: &brush_model::Press,
    ex: brush_model::Extrapolation,
    hint: &str,
) -> Result<brush_model::Footprint> {
    profile.predict(press, ex).map_err(|e| match e {
        brush_model::ProfileError::OutOfRange { profile, quantity, value, min, max } => anyhow::anyhow!(
            "{quantity} = {value:.4} is outside the calibrated range [{min:.4}, {max:.4}] of profile `{profile}` ({hint})"
        ),
        e => e.into(),
    })
}

/// Prints a value as pretty JSON on stdout.
pub fn print_json<T: serde::Serialize>(value: &T) -> Result<()> {
    outln!("{}", serde_json::to_string_pretty(value)?)
}

/// Loads an image file as coverage (ink = 1), naming the file on error.
pub fn load_image(path: &Path) -> Result<bezier_raster::Coverage> {
    Ok(bezier_raster::Coverage::load(path)?)
}

pub use maobi::pipeline::gray;

/// The table `models` and `eval-generator` print: per model, CSIM and SSIM best, worst and mean,
/// in %.
pub fn print_model_table<'a>(
    rows: impl IntoIterator<Item = (&'a str, stroke_metrics::Summary, stroke_metrics::Summary)>,
) -> Result<()> {
    crate::outln!(
        "{:<8} {:>9} {:>9} {:>9}   {:>9} {:>9} {:>9}",
        "model",
        "CSIM best",
        "worst",
        "mean",
        "SSIM best",
        "worst",
        "mean"
    )?;
    for (name, c, s) in rows {
        crate::outln!(
            "{:<8} {:>9.2} {:>9.2} {:>9.2}   {:>9.2} {:>9.2} {:>9.2}",
            name,
            100.0 * c.best,
            100.0 * c.worst,
            100.0 * c.mean,
            100.0 * s.best,
            100.0 * s.worst,
            100.0 * s.mean
        )?;
    }
    Ok(())
}

/// Seconds a loop runs before [`Progress`] prints its first line without a terminal (the
/// environment variable `MAOBI_PROGRESS_AFTER_S` overrides it): short runs stay quiet, so an
/// error stays the one line on stderr.
pub const PROGRESS_QUIET_S: f64 = 20.0;

/// Progress over items done in parallel (`write`, `evaluate`, `dataset`, …): an indicatif bar
/// when stderr is a terminal; otherwise (a log, a pipe, CI), once the loop has run
/// [`PROGRESS_QUIET_S`], a line on stderr every 5 % (`evaluate: 120/499 (24%)  elapsed 1:02
/// ETA 3:16`).
pub struct Progress {
    bar: Option<indicatif::ProgressBar>,
    what: String,
    total: u64,
    done: std::sync::atomic::AtomicU64,
    next_pct: std::sync::atomic::AtomicU64,
    quiet_s: f64,
    start: std::time::Instant,
}

impl Progress {
    /// One more item is done (`n` of them).
    pub fn inc(&self, n: u64) {
        use std::sync::atomic::Ordering::Relaxed;
        let done = self.done.fetch_add(n, Relaxed) + n;
        self.report(done);
    }

    /// `done` items are done.
    pub fn set_position(&self, done: u64) {
        self.done.store(done, std::sync::atomic::Ordering::Relaxed);
        self.report(done);
    }

    fn report(&self, done: u64) {
        use std::sync::atomic::Ordering::Relaxed;
        if let Some(pb) = &self.bar {
            pb.set_position(done);
            return;
        }
        let elapsed = self.start.elapsed().as_secs_f64();
        let pct = done.min(self.total) * 100 / self.total.max(1);
        let next = self.next_pct.load(Relaxed);
        if elapsed < self.quiet_s || pct < next {
            return;
        }
        // One thread prints each 5 % step.
        if self.next_pct.compare_exchange(next, (pct / 5 + 1) * 5, Relaxed, Relaxed).is_err() {
            return;
        }
        let eta = elapsed * (self.total.saturating_sub(done)) as f64 / done.max(1) as f64;
        eprintln!("{}: {done}/{} ({pct}%)  elapsed {}  ETA {}", self.what, self.total, clock(elapsed), clock(eta));
    }

    /// Removes the bar (lines already printed stay).
    pub fn finish_and_clear(&self) {
        if let Some(pb) = &self.bar {
            pb.finish_and_clear();
        }
    }
}

/// A [`Progress`] over `len` items, named `what`.
pub fn progress(len: u64, what: &str) -> Progress {
    use std::io::IsTerminal;
    let bar = std::io::stderr().is_terminal().then(|| {
        let pb = indicatif::ProgressBar::new(len);
        pb.set_style(
            indicatif::ProgressStyle::with_template("{msg:>10} [{bar:40}] {pos}/{len} ({per_sec}, {eta})")
                .expect("valid template")
                .progress_chars("=> "),
        );
        pb.set_message(what.to_string());
        pb
    });
    let quiet_s = std::env::var("MAOBI_PROGRESS_AFTER_S")
        .ok()
        .and_then(|v| v.parse::<f64>().ok())
        .filter(|v| v.is_finite() && *v >= 0.0)
        .unwrap_or(PROGRESS_QUIET_S);
    Progress {
        bar,
        what: what.to_string(),
        total: len,
        done: std::sync::atomic::AtomicU64::new(0),
        next_pct: std::sync::atomic::AtomicU64::new(5),
        quiet_s,
        start: std::time::Instant::now(),
    }
}

/// Progress of a long loop (`maobi train`): an indicatif bar when stderr is a terminal; otherwise
/// (a log file, a pipe, CI) one line on stderr each time another `every_pct` percent is done, with
/// the step, the caller's figures, the elapsed time and an estimate of the time left.
pub struct StepProgress {
    bar: Option<indicatif::ProgressBar>,
    what: &'static str,
    total: u64,
    every_pct: u64,
    next_pct: u64,
    start: std::time::Instant,
}

impl StepProgress {
    /// A progress report over `total` steps, named `what` (`train`).
    pub fn new(total: u64, what: &'static str, every_pct: u64) -> Self {
        use std::io::IsTerminal;
        let bar = std::io::stderr().is_terminal().then(|| {
            let pb = indicatif::ProgressBar::new(total);
            pb.set_style(
                indicatif::ProgressStyle::with_template(&format!(
                    "{what} [{{bar:40}}] {{pos}}/{{len}} {{msg}} ({{per_sec}}, {{eta}})"
                ))
                .expect("valid template")
                .progress_chars("=> "),
            );
            pb
        });
        let every_pct = every_pct.clamp(1, 100);
        StepProgress {
            bar,
            what,
            total: total.max(1),
            every_pct,
            next_pct: every_pct,
            start: std::time::Instant::now(),
        }
    }

    /// Step `done` (1-based) of the total is finished; `detail` is what to show with it
    /// (`loss 0.00123  validation 0.00110`).
    pub fn step(&mut self, done: u64, detail: &str) {
        if let Some(pb) = &self.bar {
            pb.set_message(detail.to_string());
            pb.set_position(done);
            return;
        }
        let pct = done.min(self.total) * 100 / self.total;
        if pct < self.next_pct && done < self.total {
            return;
        }
        while self.next_pct <= pct {
            self.next_pct += self.every_pct;
        }
        let elapsed = self.start.elapsed().as_secs_f64();
        let eta = elapsed * (self.total - done.min(self.total)) as f64 / done.max(1) as f64;
        eprintln!(
            "{}: step {done}/{} ({pct}%)  {detail}  elapsed {}  ETA {}",
            self.what,
            self.total,
            clock(elapsed),
            clock(eta)
        );
    }

    /// Removes the bar (the lines stay).
    pub fn finish(self) {
        if let Some(pb) = self.bar {
            pb.finish_and_clear();
        }
    }
}

/// Seconds as `m:ss` (or `h:mm:ss` from an hour).
pub fn clock(seconds: f64) -> String {
    let s = seconds.max(0.0).round() as u64;
    if s >= 3600 {
        format!("{}:{:02}:{:02}", s / 3600, s / 60 % 60, s % 60)
    } else {
        format!("{}:{:02}", s / 60, s % 60)
    }
}

/// The `--brush` argument shared by most commands.
#[derive(clap::Args, Debug, Clone)]
pub struct BrushArg {
    /// Brush: pen1, pen2 or a profile JSON file.
    #[arg(long, default_value = "pen1")]
    pub brush: String,
}

/// A flag value parsed by its type's `FromStr` (whose error message is kept), with the names
/// that parse listed by `--help` as the possible values.
#[derive(Clone)]
pub struct Named<T> {
    names: Vec<&'static str>,
    _t: std::marker::PhantomData<fn() -> T>,
}

impl<T: std::str::FromStr> Named<T> {
    /// The parser; of `candidates`, `--help` lists the ones `T` accepts.
    pub fn new(candidates: &[&'static str]) -> Self {
        Named { names: candidates.iter().copied().filter(|n| n.parse::<T>().is_ok()).collect(), _t: Default::default() }
    }
}

impl<T> clap::builder::TypedValueParser for Named<T>
where
    T: std::str::FromStr<Err = String> + Clone + Send + Sync + 'static,
{
    type Value = T;

    fn parse_ref(
        &self,
        _cmd: &clap::Command,
        arg: Option<&clap::Arg>,
        value: &std::ffi::OsStr,
    ) -> std::result::Result<T, clap::Error> {
        let flag = arg.map_or_else(|| "the value".to_string(), |a| format!("'{a}'"));
        let s = value.to_str().ok_or_else(|| {
            clap::Error::raw(clap::error::ErrorKind::InvalidUtf8, format!("invalid UTF-8 in {flag}\n"))
        })?;
        s.parse().map_err(|e| {
            clap::Error::raw(clap::error::ErrorKind::InvalidValue, format!("invalid value '{s}' for {flag}: {e}\n"))
        })
    }

    fn possible_values(&self) -> Option<Box<dyn Iterator<Item = clap::builder::PossibleValue> + '_>> {
        Some(Box::new(self.names.iter().map(|n| clap::builder::PossibleValue::new(*n))))
    }
}

/// The `--model` argument: a stroke model name (help lists `ModelKind::ALL`).
pub fn parse_model() -> Named<bezier_raster::ModelKind> {
    let names: Vec<&'static str> = bezier_raster::ModelKind::ALL.iter().map(|m| m.name()).collect();
    Named::new(&names)
}

/// The `--from` argument: a centre-line method name (help lists those this build knows).
pub fn parse_method() -> Named<trajectory::Method> {
    Named::new(&["medians", "skeleton", "template"])
}

/// The press arguments shared by `footprint` and `stroke`: depth in mm, angles in degrees.
#[derive(clap::Args, Debug, Clone, Copy)]
pub struct PressArgs {
    /// Press depth h, mm.
    #[arg(long = "h", value_name = "MM", allow_negative_numbers = true)]
    pub h_mm: f64,
    /// Tilt α, degrees.
    #[arg(long = "alpha", value_name = "DEG", allow_negative_numbers = true)]
    pub alpha_deg: f64,
    /// Rotation β, degrees.
    #[arg(long = "beta", value_name = "DEG", default_value_t = 0.0, allow_negative_numbers = true)]
    pub beta_deg: f64,
}

impl PressArgs {
    /// The press, angles converted to radians, after checking each value against what the
    /// brush can physically do (even with `--extrapolate`): depth 0 up to the bundle's length,
    /// tilt within ±90°, rotation within ±360°.
    pub fn press(&self, profile: &BrushProfile) -> Result<brush_model::Press> {
        check_range("--h", self.h_mm, 0.0, profile.brush.length_mm, "mm (up to the brush's length)")?;
        check_range("--alpha", self.alpha_deg, -90.0, 90.0, "degrees")?;
        check_range("--beta", self.beta_deg, -360.0, 360.0, "degrees")?;
        Ok(brush_model::Press::from_degrees(self.h_mm, self.alpha_deg, self.beta_deg))
    }
}

/// One row of a stroke-photo labels file.
pub struct StrokeLabel {
    /// Image file, relative to the labels' folder.
    pub file: String,
    /// The press that made the stroke.
    pub press: brush_model::Press,
    /// Scale of this photo, when given.
    pub px_per_mm: Option<f64>,
}

/// Reads `file,h_mm,alpha_deg,beta_deg[,px_per_mm]` (extra columns ignored); errors name the
/// file, line and column.
pub fn read_stroke_labels(path: &Path) -> Result<Vec<StrokeLabel>> {
    const MAX_BYTES: u64 = 64 << 20;
    const MAX_ROWS: usize = 100_000;
    let name = path.display().to_string();
    let len = std::fs::metadata(path).with_context(|| format!("{name}: cannot read"))?.len();
    if len > MAX_BYTES {
        bail!("{name}: {len} bytes; a labels file is at most {MAX_BYTES} bytes");
    }
    let mut rdr = csv::ReaderBuilder::new()
        .trim(csv::Trim::All)
        .from_path(path)
        .with_context(|| format!("{name}: cannot read"))?;
    let header = rdr.headers().with_context(|| format!("{name}: cannot read the header"))?.clone();
    let col = |c: &str| header.iter().position(|h| h == c);
    let need = |c: &'static str| {
        col(c).with_context(|| format!("{name}: header has no column `{c}` (need file,h_mm,alpha_deg,beta_deg)"))
    };
    let (fi, hi, ai, bi) = (need("file")?, need("h_mm")?, need("alpha_deg")?, need("beta_deg")?);
    let si = col("px_per_mm");
    let mut out = Vec::new();
    for rec in rdr.records() {
        let rec = rec.with_context(|| format!("{name}: malformed CSV"))?;
        if out.len() == MAX_ROWS {
            bail!("{name}: more than {MAX_ROWS} rows");
        }
        let line = rec.position().map_or(0, |p| p.line());
        let num = |i: usize, c: &str| -> Result<f64> {
            let v = rec.get(i).unwrap_or("");
            v.parse::<f64>()
                .ok()
                .filter(|x| x.is_finite())
                .with_context(|| format!("{name}: line {line}, column `{c}`: expected a number, got {v:?}"))
        };
        let px = match si {
            Some(i) if !rec.get(i).unwrap_or("").is_empty() => Some(num(i, "px_per_mm")?),
            _ => None,
        };
        out.push(StrokeLabel {
            file: rec.get(fi).unwrap_or("").to_string(),
            press: brush_model::Press::from_degrees(num(hi, "h_mm")?, num(ai, "alpha_deg")?, num(bi, "beta_deg")?),
            px_per_mm: px,
        });
    }
    if out.is_empty() {
        anyhow::bail!("{name}: no rows");
    }
    Ok(out)
}

/// `--renderer analytic|neural` and `--generator` of `maobi write`.
#[derive(clap::Args, Debug, Clone)]
pub struct RendererArgs {
    /// Who draws the character: `analytic` (the --model stroke model) or `neural` (the trained
    /// generator, batched along the track; it must have been trained for --brush).
    #[arg(long, default_value = "analytic", value_parser = ["analytic", "neural"])]
    pub renderer: String,
    /// Generator weights (`.safetensors`, its `.json` config beside) for `--renderer neural`
    /// (default: the committed pen1 generator).
    #[arg(long, value_name = "FILE")]
    pub generator: Option<std::path::PathBuf>,
}

impl RendererArgs {
    /// Whether the neural generator draws.
    pub fn neural(&self) -> bool {
        self.renderer == "neural"
    }

    /// The generator asked for (or the committed pen1 model).
    pub fn generator(&self) -> Result<neural_gen::Generator> {
        maobi::generator::load_generator(self.generator.as_deref())
    }
}

/// `--renderer analytic|neural` and `--generator` of `maobi stroke`.
#[derive(clap::Args, Debug, Clone)]
pub struct StrokeRendererArgs {
    /// Who draws the footprint: `analytic` (the --model stroke model, PNG or SVG at any size and
    /// scale) or `neural` (the trained generator: PNG only, at its own size and scale, inside its
    /// training range).
    #[arg(long, default_value = "analytic", value_parser = ["analytic", "neural"])]
    pub renderer: String,
    /// Generator weights (`.safetensors`, its `.json` config beside) for `--renderer neural`
    /// (default: the committed pen1 generator).
    #[arg(long, value_name = "FILE")]
    pub generator: Option<std::path::PathBuf>,
}

impl StrokeRendererArgs {
    /// Whether the neural generator draws.
    pub fn neural(&self) -> bool {
        self.renderer == "neural"
    }

    /// The generator asked for (or the committed pen1 model).
    pub fn generator(&self) -> Result<neural_gen::Generator> {
        maobi::generator::load_generator(self.generator.as_deref())
    }
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

/// Refuses an existing non-empty output folder (a file, or a folder with anything in it) unless
/// `force`; with `force`, refuses anything but a folder. `flag` names the output in errors.
///
/// # Errors
/// As described, naming the flag and the path.
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
