//! The real GRBL 1.1h firmware, compiled for the host by grbl-sim from the sources vendored in
//! `third_party/grbl` (GPL-3.0, outside every packed crate), on a pseudo-terminal, behind a
//! relay that can count the bytes in flight and inject faults.
//!
//! Used by robot-grbl's tests and (through `#[path]`) by maobi's CLI test.

#![allow(dead_code, unreachable_pub)]

use std::collections::VecDeque;
use std::hash::{Hash, Hasher};
use std::io::{Read, Write};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex, OnceLock};
use std::time::{Duration, Instant};

use serialport::{SerialPort, TTYPort};

/// The vendored sources.
fn sources() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../third_party/grbl/grbl")
}

/// The built firmware simulator and validator.
pub struct Firmware {
    pub sim: PathBuf,
    pub validator: PathBuf,
}

static BUILT: OnceLock<Result<Firmware, String>> = OnceLock::new();

/// The firmware, built once per run (cached under the target folder by the sources' hash), or
/// `None` with `SKIPPED <test>: <why>` printed where it cannot be built (no C compiler, or the
/// sources are not there as in a packed crate).
pub fn firmware(test: &str) -> Option<&'static Firmware> {
    match BUILT.get_or_init(build) {
        Ok(f) => Some(f),
        Err(why) => {
            println!("SKIPPED {test}: {why}");
            None
        }
    }
}

fn compiler() -> String {
    std::env::var("CC").unwrap_or_else(|_| "cc".into())
}

/// Every file under `dir`, sorted.
fn files(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(rd) = std::fs::read_dir(dir) else { return };
    let mut entries: Vec<PathBuf> = rd.filter_map(|e| e.ok().map(|e| e.path())).collect();
    entries.sort();
    for p in entries {
        if p.is_dir() {
            files(&p, out);
        } else {
            out.push(p);
        }
    }
}

fn build() -> Result<Firmware, String> {
    let src = sources();
    if !src.join("grbl-sim/simulator.c").is_file() {
        return Err(format!("the GRBL sources are not at {} (a packed crate has none)", src.display()));
    }
    let cc = compiler();
    match Command::new(&cc).arg("--version").stdout(Stdio::null()).stderr(Stdio::null()).status() {
        Ok(s) if s.success() => {}
        _ => return Err(format!("no C compiler (`{cc} --version` failed; set CC)")),
    }
    let mut all = Vec::new();
    files(&src, &mut all);
    let mut h = std::hash::DefaultHasher::new();
    cc.hash(&mut h);
    for f in &all {
        f.strip_prefix(&src).unwrap_or(f).hash(&mut h);
        std::fs::read(f).map_err(|e| format!("{}: {e}", f.display()))?.hash(&mut h);
    }
    let root = PathBuf::from(env!("CARGO_TARGET_TMPDIR"));
    let out = root.join(format!("grbl-sim-{:016x}", h.finish()));
    let done = Firmware { sim: out.join("grbl_sim.exe"), validator: out.join("gvalidate.exe") };
    if done.sim.is_file() && done.validator.is_file() {
        return Ok(done);
    }
    let work = root.join(format!("grbl-sim-build-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&work);
    std::fs::create_dir_all(&work).map_err(|e| format!("{}: {e}", work.display()))?;
    let sim_dir = src.join("grbl-sim");
    // As grbl-sim's Makefile: (object, source relative to grbl-sim/, extra -include).
    let base = [
        "protocol",
        "planner",
        "settings",
        "print",
        "nuts_bolts",
        "stepper",
        "gcode",
        "spindle_control",
        "motion_control",
        "limits",
        "coolant_control",
        "probe",
        "system",
        "jog",
    ];
    let mut units: Vec<(String, String, Option<&str>)> = Vec::new();
    for b in base {
        let inc = match b {
            "planner" => Some("planner_inject_accessors.c"),
            "stepper" => Some("stepper_hooks.h"),
            _ => None,
        };
        units.push((format!("grbl_{b}.o"), format!("../{b}.c"), inc));
    }
    units.push(("grbl_main.o".into(), "../main.c".into(), Some("rename_main.h")));
    units.push(("grbl_serial.o".into(), "../serial.c".into(), Some("serial_hooks.h")));
    units.push(("grbl_report.o".into(), "../report.c".into(), None));
    units.push(("overridden_report.o".into(), "../report.c".into(), Some("rename_report_status_message.h")));
    for s in [
        "avr/interrupt",
        "avr/pgmspace",
        "avr/io",
        "avr/eeprom",
        "grbl_eeprom_extensions",
        "main",
        "simulator",
        "serial",
        "util/delay",
        "util/floatunsisf",
        "platform_LINUX",
        "system_declares",
        "grbl_interface",
        "validator",
    ] {
        units.push((format!("sim_{}.o", s.replace('/', "_")), format!("{s}.c"), None));
    }
    let compile = |(obj, c, inc): &(String, String, Option<&str>)| {
        let mut cmd = Command::new(&cc);
        cmd.current_dir(&sim_dir).args([
            "-O2",
            "-w",
            "-fcommon",
            "-DF_CPU=16000000",
            "-include",
            "config.h",
            "-I.",
            "-DPLAT_LINUX",
        ]);
        if let Some(i) = inc {
            cmd.args(["-include", i]);
        }
        cmd.args(["-c", c, "-o"]).arg(work.join(obj));
        cmd
    };
    // Two at a time (the machine has two cores).
    for pair in units.chunks(2) {
        let mut children = Vec::new();
        for u in pair {
            children.push((u.1.clone(), compile(u).output_spawn()?));
        }
        for (c, child) in children {
            let out = child.wait_with_output().map_err(|e| e.to_string())?;
            if !out.status.success() {
                return Err(format!("compiling {c} failed: {}", String::from_utf8_lossy(&out.stderr)));
            }
        }
    }
    let objs = |names: &[&str]| -> Vec<PathBuf> { names.iter().map(|n| work.join(n)).collect() };
    let base_objs: Vec<String> = base.iter().map(|b| format!("grbl_{b}.o")).collect();
    let avr = [
        "sim_avr_interrupt.o",
        "sim_avr_pgmspace.o",
        "sim_avr_io.o",
        "sim_avr_eeprom.o",
        "sim_grbl_eeprom_extensions.o",
    ];
    let mut sim_objs: Vec<&str> = vec!["sim_grbl_interface.o", "grbl_main.o", "grbl_serial.o", "grbl_report.o"];
    sim_objs.extend([
        "sim_main.o",
        "sim_simulator.o",
        "sim_serial.o",
        "sim_util_delay.o",
        "sim_util_floatunsisf.o",
        "sim_platform_LINUX.o",
        "sim_system_declares.o",
    ]);
    sim_objs.extend(avr);
    sim_objs.extend(base_objs.iter().map(String::as_str));
    let mut val_objs: Vec<&str> = vec!["sim_validator.o", "overridden_report.o", "sim_system_declares.o"];
    val_objs.extend(avr);
    val_objs.extend(base_objs.iter().map(String::as_str));
    for (exe, list) in [("grbl_sim.exe", &sim_objs), ("gvalidate.exe", &val_objs)] {
        let out = Command::new(&cc)
            .arg("-fcommon")
            .arg("-o")
            .arg(work.join(exe))
            .args(objs(list))
            .args(["-lm", "-lrt", "-pthread"])
            .output()
            .map_err(|e| e.to_string())?;
        if !out.status.success() {
            return Err(format!("linking {exe} failed: {}", String::from_utf8_lossy(&out.stderr)));
        }
    }
    // Into place at once; another test binary may have got there first.
    if std::fs::rename(&work, &out).is_err() {
        let _ = std::fs::remove_dir_all(&work);
    }
    if done.sim.is_file() && done.validator.is_file() {
        Ok(done)
    } else {
        Err(format!("the built firmware is not at {}", out.display()))
    }
}

trait SpawnOutput {
    fn output_spawn(&mut self) -> Result<Child, String>;
}

impl SpawnOutput for Command {
    fn output_spawn(&mut self) -> Result<Child, String> {
        self.stdout(Stdio::null()).stderr(Stdio::piped()).spawn().map_err(|e| e.to_string())
    }
}

/// Runs the validator on `text`: `Ok(())`, or the line number and GRBL's answer.
pub fn validate(fw: &Firmware, text: &str) -> Result<(), String> {
    let dir = tempfile::tempdir().map_err(|e| e.to_string())?;
    let file = dir.path().join("program.nc");
    std::fs::write(&file, text).map_err(|e| e.to_string())?;
    let out = Command::new(&fw.validator).arg(&file).current_dir(dir.path()).output().map_err(|e| e.to_string())?;
    let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    if out.status.success() && !stdout.contains("error") {
        Ok(())
    } else {
        // gvalidate answers a line per line; the first `error:` is the line that failed.
        let lines: Vec<&str> = stdout.lines().filter(|l| !l.starts_with('[')).collect();
        let at = lines.iter().position(|l| l.starts_with("error"));
        Err(format!(
            "gvalidate exit {:?}, answer {:?} at statement {:?}",
            out.status.code(),
            at.map(|i| lines[i]),
            at.map(|i| i + 1)
        ))
    }
}

/// A fault the relay injects.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Inject {
    /// Nothing.
    None,
    /// Close the host's side after this many `ok`s (the cable pulled).
    CloseAfterOks(usize),
    /// Send GRBL a soft reset once a status report has the machine below this Z, machine mm
    /// (its reset button, pressed while the brush writes).
    ResetBelowZ(f64),
    /// Replace the first letter of the line sent after this many `ok`s by `Q` (noise).
    CorruptAfterOks(usize),
    /// Pass nothing more from GRBL to the host after this many `ok`s (a link gone quiet: the
    /// host's bytes still reach GRBL).
    MuteAfterOks(usize),
}

/// What the relay saw.
#[derive(Default)]
pub struct Seen {
    pub oks: AtomicUsize,
    /// The most bytes sent to GRBL and not yet answered.
    pub max_in_flight: AtomicUsize,
    pub injected: AtomicBool,
    /// GRBL's output, for messages.
    pub from_grbl: Mutex<Vec<u8>>,
}

/// GRBL running, with a device for the host.
pub struct Machine {
    child: Child,
    /// The firmware's working folder (its EEPROM file) and output files.
    pub dir: tempfile::TempDir,
    /// The pseudo-terminal the host opens (`/dev/pts/N`).
    pub device: String,
    grbl: Option<TTYPort>,
    _grbl_slave: TTYPort,
    host: Option<TTYPort>,
    _host_slave: TTYPort,
    relay: Option<std::thread::JoinHandle<(TTYPort, Option<TTYPort>)>>,
    stop: Arc<AtomicBool>,
    pub seen: Arc<Seen>,
}

impl Machine {
    /// Starts the firmware (fresh EEPROM: defaults) and sends it `setup` (settings, offsets),
    /// each line answered `ok`, before the host is let in.
    pub fn start(fw: &Firmware, setup: &[&str]) -> Machine {
        let dir = tempfile::tempdir().expect("temp dir");
        let (grbl, grbl_slave) = TTYPort::pair().expect("a pseudo-terminal for GRBL");
        let slave_path = grbl_slave.name().expect("its name");
        let open = || std::fs::OpenOptions::new().read(true).write(true).open(&slave_path).expect("open the slave");
        let child = Command::new(&fw.sim)
            .args(["-n", "-s", "/dev/null", "-b"])
            .arg(dir.path().join("blocks.txt"))
            .current_dir(dir.path())
            .stdin(Stdio::from(open()))
            .stdout(Stdio::from(open()))
            .stderr(Stdio::null())
            .spawn()
            .expect("start grbl_sim");
        let (host, host_slave) = TTYPort::pair().expect("a pseudo-terminal for the host");
        let device = host_slave.name().expect("its name");
        let mut m = Machine {
            child,
            dir,
            device,
            grbl: Some(grbl),
            _grbl_slave: grbl_slave,
            host: Some(host),
            _host_slave: host_slave,
            relay: None,
            stop: Arc::new(AtomicBool::new(false)),
            seen: Arc::new(Seen::default()),
        };
        m.wait_for("Grbl 1.1h", Duration::from_secs(10));
        for s in setup {
            m.command(s);
        }
        m
    }

    /// Reads GRBL's output until `what` appears.
    fn wait_for(&mut self, what: &str, within: Duration) -> String {
        let g = self.grbl.as_mut().expect("not relaying");
        let deadline = Instant::now() + within;
        let mut got = Vec::new();
        let mut buf = [0u8; 256];
        g.set_timeout(Duration::from_millis(20)).unwrap();
        let mut last_err = None;
        while Instant::now() < deadline {
            match g.read(&mut buf) {
                Err(e) => last_err = Some(e.to_string()),
                Ok(n) => {
                    got.extend_from_slice(&buf[..n]);
                    if String::from_utf8_lossy(&got).contains(what) {
                        return String::from_utf8_lossy(&got).into_owned();
                    }
                }
            }
        }
        panic!(
            "GRBL did not say {what:?} in {within:?}: {:?} (the firmware: {:?}, {last_err:?})",
            String::from_utf8_lossy(&got),
            self.child.try_wait()
        );
    }

    /// Sends a line straight to GRBL (not relaying) and waits for `ok`; returns what came.
    pub fn command(&mut self, line: &str) -> String {
        self.grbl.as_mut().expect("not relaying").write_all(format!("{line}\n").as_bytes()).unwrap();
        let got = self.wait_for("ok\r\n", Duration::from_secs(10));
        assert!(!got.contains("error"), "GRBL refused {line:?}: {got}");
        got
    }

    /// Sends raw bytes straight to GRBL and returns what it says within `wait`.
    pub fn raw(&mut self, bytes: &[u8], wait: Duration) -> String {
        let g = self.grbl.as_mut().expect("not relaying");
        g.write_all(bytes).unwrap();
        let deadline = Instant::now() + wait;
        let mut got = Vec::new();
        let mut buf = [0u8; 256];
        g.set_timeout(Duration::from_millis(20)).unwrap();
        while Instant::now() < deadline {
            if let Ok(n) = g.read(&mut buf) {
                got.extend_from_slice(&buf[..n]);
            }
        }
        String::from_utf8_lossy(&got).into_owned()
    }

    /// A status report, asked straight (not relaying).
    pub fn status(&mut self) -> String {
        for _ in 0..20 {
            let got = self.raw(b"?", Duration::from_millis(150));
            if let Some(s) = got.lines().rev().find(|l| l.starts_with('<') && l.ends_with('>')) {
                return s.to_string();
            }
        }
        panic!("no status report");
    }

    /// Relays bytes between the host's device and GRBL, counting the bytes in flight and
    /// injecting `inject`.
    pub fn relay(&mut self, inject: Inject) {
        let mut grbl = self.grbl.take().expect("relaying already");
        let mut host = self.host.take();
        let (stop, seen) = (self.stop.clone(), self.seen.clone());
        grbl.set_timeout(Duration::from_millis(5)).unwrap();
        if let Some(h) = host.as_mut() {
            h.set_timeout(Duration::from_millis(5)).unwrap();
        }
        self.relay = Some(std::thread::spawn(move || {
            let mut buf = [0u8; 512];
            let mut lines: VecDeque<usize> = VecDeque::new();
            let mut partial = 0usize;
            let mut from_grbl_line = Vec::new();
            let mut pending_corrupt = false;
            let mut muted = false;
            while !stop.load(Ordering::SeqCst) {
                let mut idle = true;
                if let Some(h) = host.as_mut() {
                    match h.read(&mut buf) {
                        Ok(n) if n > 0 => {
                            idle = false;
                            let mut bytes = buf[..n].to_vec();
                            for b in bytes.iter_mut() {
                                match *b {
                                    // Realtime commands never enter GRBL's buffer.
                                    b'?' | b'!' | b'~' => {}
                                    0x18 => {
                                        lines.clear();
                                        partial = 0;
                                    }
                                    0x80.. => {}
                                    b'\n' => {
                                        lines.push_back(partial + 1);
                                        partial = 0;
                                    }
                                    _ => {
                                        if pending_corrupt && partial == 0 {
                                            *b = b'Q';
                                            pending_corrupt = false;
                                            seen.injected.store(true, Ordering::SeqCst);
                                        }
                                        partial += 1;
                                    }
                                }
                            }
                            let in_flight = lines.iter().sum::<usize>() + partial;
                            seen.max_in_flight.fetch_max(in_flight, Ordering::SeqCst);
                            if grbl.write_all(&bytes).is_err() {
                                break;
                            }
                        }
                        Ok(_) => {}
                        Err(e) if e.kind() == std::io::ErrorKind::TimedOut => {}
                        // The host closed its side: nothing to read until it opens again.
                        Err(_) => std::thread::sleep(Duration::from_millis(5)),
                    }
                }
                match grbl.read(&mut buf) {
                    Ok(n) if n > 0 => {
                        idle = false;
                        seen.from_grbl.lock().unwrap().extend_from_slice(&buf[..n]);
                        let mut close_at = None;
                        for (i, &b) in buf[..n].iter().enumerate() {
                            if b == b'\n' {
                                let l = String::from_utf8_lossy(&from_grbl_line).trim().to_string();
                                from_grbl_line.clear();
                                if let Inject::ResetBelowZ(z) = inject
                                    && l.starts_with("<Run")
                                    && !seen.injected.load(Ordering::SeqCst)
                                    && mpos(&l)[2] < z
                                {
                                    let _ = grbl.write_all(&[0x18]);
                                    seen.injected.store(true, Ordering::SeqCst);
                                }
                                if l == "ok" || l.starts_with("error:") {
                                    lines.pop_front();
                                    if l == "ok" {
                                        let oks = seen.oks.fetch_add(1, Ordering::SeqCst) + 1;
                                        match inject {
                                            Inject::CloseAfterOks(k) if oks == k => close_at = Some(i + 1),
                                            Inject::CorruptAfterOks(k) if oks == k => pending_corrupt = true,
                                            Inject::MuteAfterOks(k) if oks == k => close_at = Some(i + 1),
                                            _ => {}
                                        }
                                    }
                                }
                            } else {
                                from_grbl_line.push(b);
                            }
                        }
                        // The host reads what came up to that `ok`, then the link is cut.
                        let upto = if muted { 0 } else { close_at.unwrap_or(n) };
                        if let Some(h) = host.as_mut()
                            && h.write_all(&buf[..upto]).is_err()
                        {
                            host = None;
                        }
                        if close_at.is_some() {
                            if let Inject::MuteAfterOks(_) = inject {
                                muted = true;
                            } else {
                                std::thread::sleep(Duration::from_millis(300));
                                host = None;
                            }
                            seen.injected.store(true, Ordering::SeqCst);
                        }
                    }
                    Ok(_) => {}
                    Err(e) if e.kind() == std::io::ErrorKind::TimedOut => {}
                    Err(_) => break,
                }
                if idle {
                    std::thread::sleep(Duration::from_millis(1));
                }
            }
            (grbl, host)
        }));
    }

    /// Stops relaying; GRBL can be talked to straight again.
    pub fn stop_relay(&mut self) {
        self.stop.store(true, Ordering::SeqCst);
        if let Some(h) = self.relay.take() {
            let (grbl, host) = h.join().expect("the relay");
            self.grbl = Some(grbl);
            self.host = host;
        }
        self.stop.store(false, Ordering::SeqCst);
    }

    /// Waits until GRBL reports Idle (the queue run out), straight.
    pub fn wait_idle(&mut self, within: Duration) -> String {
        let deadline = Instant::now() + within;
        loop {
            let s = self.status();
            if s.starts_with("<Idle") || Instant::now() > deadline {
                return s;
            }
            std::thread::sleep(Duration::from_millis(100));
        }
    }

    /// Ends the firmware cleanly (Ctrl-F: it exits once idle, flushing its files) and returns
    /// the executed blocks: each planned block's end, machine steps per axis.
    pub fn finish(mut self) -> Vec<[i64; 3]> {
        self.stop_relay();
        if let Some(g) = self.grbl.as_mut() {
            let _ = g.write_all(&[0x06]);
        }
        // On a loaded machine (the whole test suite on 2 cores) the simulator can take a while
        // to run its queue out; killed before it exits, its buffered block file is cut short.
        let deadline = Instant::now() + Duration::from_secs(60);
        while Instant::now() < deadline {
            if let Ok(Some(_)) = self.child.try_wait() {
                break;
            }
            std::thread::sleep(Duration::from_millis(20));
        }
        let _ = self.child.kill();
        let _ = self.child.wait();
        let text = std::fs::read_to_string(self.dir.path().join("blocks.txt")).unwrap_or_default();
        text.lines()
            .filter_map(|l| {
                let v: Vec<i64> = l.split(',').take(3).filter_map(|x| x.trim().parse().ok()).collect();
                (v.len() == 3).then(|| [v[0], v[1], v[2]])
            })
            .collect()
    }
}

impl Drop for Machine {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::SeqCst);
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// A serial-to-TCP bridge on loopback (as ser2net or an ESP32 bridge serves a board): accepts
/// one connection and passes bytes between it and the machine's device until either side
/// closes. Returns `HOST:PORT`.
pub fn tcp_bridge(device: &str) -> String {
    let listener = std::net::TcpListener::bind("127.0.0.1:0").expect("a loopback port");
    let addr = listener.local_addr().unwrap().to_string();
    let mut tty = serialport::new(device, 115_200).timeout(Duration::from_millis(5)).open().expect("the device");
    std::thread::spawn(move || {
        let Ok((mut sock, _)) = listener.accept() else { return };
        sock.set_read_timeout(Some(Duration::from_millis(5))).unwrap();
        let mut buf = [0u8; 512];
        loop {
            match sock.read(&mut buf) {
                Ok(0) => return,
                Ok(n) => {
                    if tty.write_all(&buf[..n]).is_err() {
                        return;
                    }
                }
                Err(e) if matches!(e.kind(), std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut) => {}
                Err(_) => return,
            }
            match tty.read(&mut buf) {
                Ok(n) if n > 0 => {
                    if sock.write_all(&buf[..n]).is_err() {
                        return;
                    }
                }
                Ok(_) => {}
                Err(e) if e.kind() == std::io::ErrorKind::TimedOut => {}
                Err(_) => return,
            }
        }
    });
    addr
}

/// The machine position of a status report (`MPos`).
pub fn mpos(status: &str) -> [f64; 3] {
    let m = status.split('|').find_map(|f| f.strip_prefix("MPos:")).unwrap_or_else(|| panic!("no MPos in {status}"));
    let v: Vec<f64> = m.split(',').map(|x| x.parse().unwrap()).collect();
    [v[0], v[1], v[2]]
}
