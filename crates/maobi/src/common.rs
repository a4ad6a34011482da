//! Helpers shared by the subcommands: brush selection, atomic file output, stdout that ends
//! quietly when the reader goes away, Ctrl-C clean-up, and numeric flag ranges.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

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
        remove_temps();
        eprintln!("error: interrupted");
        std::process::exit(130);
    })
    .context("cannot install the Ctrl-C handler")
}

/// Asks the Ctrl-C handler to let this command stop by itself: it polls [`interrupted`].
pub fn stop_on_interrupt() {
    COOPERATIVE.store(true, Ordering::SeqCst);
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
struct TempGuard(PathBuf);

impl TempGuard {
    fn new(p: &Path) -> Self {
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
