//! Progress of long loops: a bar on a terminal, plain lines otherwise.

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
