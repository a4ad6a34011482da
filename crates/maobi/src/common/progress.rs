//! Progress of long loops: a bar on a terminal, plain lines otherwise.

/// Seconds a loop runs before [`Progress`] prints its first line without a terminal (the
/// environment variable `MAOBI_PROGRESS_AFTER_S` overrides it): short runs stay quiet, so an
/// error stays the one line on stderr.
pub const PROGRESS_QUIET_S: f64 = 20.0;

/// Progress over items done in parallel (`write`, `evaluate`, `dataset`, …) or over the steps
/// of a long loop (`train`, [`step_progress`]): an indicatif bar when stderr is a terminal;
/// otherwise (a log, a pipe, CI), once the loop has run [`PROGRESS_QUIET_S`] (at once for
/// steps), a line on stderr every 5 % (`evaluate: 120/499 (24%)  elapsed 1:02  ETA 3:16`;
/// `train: step 125/2500 (5%)  loss 0.00123  elapsed 0:41  ETA 13:00`).
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
        self.report(done, None);
    }

    /// `done` items are done.
    pub fn set_position(&self, done: u64) {
        self.done.store(done, std::sync::atomic::Ordering::Relaxed);
        self.report(done, None);
    }

    /// Step `done` (1-based) is finished; `detail` is what to show with it (`loss 0.00123`).
    pub fn step(&self, done: u64, detail: &str) {
        self.done.store(done, std::sync::atomic::Ordering::Relaxed);
        self.set_message(detail.to_string());
        self.report(done, Some(detail));
    }

    fn report(&self, done: u64, step: Option<&str>) {
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
        let eta = clock(elapsed * (self.total.saturating_sub(done)) as f64 / done.max(1) as f64);
        let (what, total, elapsed) = (&self.what, self.total, clock(elapsed));
        match step {
            Some(detail) => eprintln!("{what}: step {done}/{total} ({pct}%)  {detail}  elapsed {elapsed}  ETA {eta}"),
            None => eprintln!("{what}: {done}/{total} ({pct}%)  elapsed {elapsed}  ETA {eta}"),
        }
    }

    /// The words beside the bar on a terminal (nothing without one).
    pub fn set_message(&self, msg: String) {
        if let Some(pb) = &self.bar {
            pb.set_message(msg);
        }
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
    let quiet_s = std::env::var("MAOBI_PROGRESS_AFTER_S")
        .ok()
        .and_then(|v| v.parse::<f64>().ok())
        .filter(|v| v.is_finite() && *v >= 0.0)
        .unwrap_or(PROGRESS_QUIET_S);
    let p = new_progress(len, what, "{msg:>10} [{bar:40}] {pos}/{len} ({per_sec}, {eta})", quiet_s);
    p.set_message(what.to_string());
    p
}

/// A [`Progress`] over the `total` steps of a long loop named `what` (`train`), reported with
/// [`Progress::step`]: its lines start at once.
pub fn step_progress(total: u64, what: &str) -> Progress {
    new_progress(total, what, &format!("{what} [{{bar:40}}] {{pos}}/{{len}} {{msg}} ({{per_sec}}, {{eta}})"), 0.0)
}

fn new_progress(len: u64, what: &str, template: &str, quiet_s: f64) -> Progress {
    use std::io::IsTerminal;
    let bar = std::io::stderr().is_terminal().then(|| {
        let pb = indicatif::ProgressBar::new(len);
        pb.set_style(indicatif::ProgressStyle::with_template(template).expect("valid template").progress_chars("=> "));
        pb
    });
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

/// Seconds as `m:ss` (or `h:mm:ss` from an hour).
pub fn clock(seconds: f64) -> String {
    let s = seconds.max(0.0).round() as u64;
    if s >= 3600 {
        format!("{}:{:02}:{:02}", s / 3600, s / 60 % 60, s % 60)
    } else {
        format!("{}:{:02}", s / 60, s % 60)
    }
}
