//! The simulator's sockets: the listeners, at most [`SimOptions::max_connections`] connections
//! at once, and each connection closed after [`SimOptions::idle_timeout`] without a byte that
//! is not whitespace. When every place is taken, a new connection takes the place of the one
//! that has gone longest without a request answered (at least [`EVICT_AFTER`]): idle
//! connections cannot lock well-formed clients out.
//!
//! [`SimOptions::max_connections`]: super::SimOptions::max_connections
//! [`SimOptions::idle_timeout`]: super::SimOptions::idle_timeout

use std::io::{Read, Write};
use std::net::{SocketAddr, TcpListener, TcpStream};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Mutex, PoisonError};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use super::Listen;
use super::dispatch::Shared;
use super::session::Session;
use crate::RobotError;
use crate::wire::Transport;

/// How long a connection must have gone without a request answered before a new connection
/// may take its place when every place is taken.
pub const EVICT_AFTER: Duration = Duration::from_secs(1);

/// One served connection, as the accepting thread sees it.
struct Slot {
    /// When it last had a request answered (or was accepted), ms since the server started.
    progress_ms: AtomicU64,
    /// Set to close it (its place is given to a new connection).
    evict: AtomicBool,
}

/// The connections being served.
type Slots = Arc<Mutex<Vec<Arc<Slot>>>>;

/// Every listener's transports and address.
pub(super) type Bound = Vec<(Vec<Transport>, SocketAddr)>;

/// Binds every listener and starts the thread that accepts connections.
pub(super) fn listen(
    listen: &[Listen],
    shared: Arc<Shared>,
    stop: Arc<AtomicBool>,
) -> Result<(JoinHandle<()>, Bound), RobotError> {
    let mut listeners = Vec::new();
    let mut addrs = Vec::new();
    for l in listen {
        let io = |source| RobotError::Io { context: l.bind.to_string(), source };
        let listener = TcpListener::bind(&l.bind).map_err(io)?;
        let addr = listener.local_addr().map_err(io)?;
        listener.set_nonblocking(true).map_err(io)?;
        addrs.push((l.transports.clone(), addr));
        listeners.push((listener, l.transports.clone()));
    }
    let thread = std::thread::spawn(move || {
        let start = Instant::now();
        let slots: Slots = Arc::default();
        while !stop.load(Ordering::SeqCst) {
            let mut idle = true;
            for (listener, transports) in &listeners {
                let Ok((stream, _)) = listener.accept() else { continue };
                idle = false;
                let now_ms = start.elapsed().as_millis() as u64;
                // Every place taken: the connection longest without an answer gives up its
                // place, if it has gone that way long enough; otherwise the new one is closed at
                // once (dropping the stream), nothing read.
                if shared.connections.load(Ordering::SeqCst) >= shared.options.max_connections {
                    let mut list = slots.lock().unwrap_or_else(PoisonError::into_inner);
                    let victim = list
                        .iter()
                        .enumerate()
                        .filter(|(_, s)| !s.evict.load(Ordering::SeqCst))
                        .min_by_key(|(_, s)| s.progress_ms.load(Ordering::SeqCst))
                        .filter(|(_, s)| {
                            now_ms.saturating_sub(s.progress_ms.load(Ordering::SeqCst))
                                >= EVICT_AFTER.as_millis() as u64
                        })
                        .map(|(i, _)| i);
                    match victim {
                        Some(i) => list.remove(i).evict.store(true, Ordering::SeqCst),
                        None => continue,
                    }
                }
                let slot = Arc::new(Slot { progress_ms: AtomicU64::new(now_ms), evict: AtomicBool::new(false) });
                slots.lock().unwrap_or_else(PoisonError::into_inner).push(slot.clone());
                shared.connections.fetch_add(1, Ordering::SeqCst);
                let (shared, stop, transports, slots) =
                    (shared.clone(), stop.clone(), transports.clone(), slots.clone());
                std::thread::spawn(move || {
                    serve(stream, &transports, &shared, &stop, &slot, start);
                    slots.lock().unwrap_or_else(PoisonError::into_inner).retain(|s| !Arc::ptr_eq(s, &slot));
                    shared.connections.fetch_sub(1, Ordering::SeqCst);
                });
            }
            if idle {
                std::thread::sleep(Duration::from_millis(5));
            }
        }
    });
    Ok((thread, addrs))
}

/// Serves one connection until the peer closes it, it stays idle too long (whitespace does not
/// count), the session closes it, its place is given to another connection, or the simulator
/// stops.
fn serve(
    mut stream: TcpStream,
    transports: &[Transport],
    shared: &Shared,
    stop: &AtomicBool,
    slot: &Slot,
    start: Instant,
) {
    let idle = shared.options.idle_timeout;
    let _ = stream.set_read_timeout(Some(Duration::from_millis(50)));
    // A peer that does not read its answers cannot hold the thread longer than this.
    let _ = stream.set_write_timeout(Some(idle));
    let _ = stream.set_nodelay(true);
    let delay = shared.options.faults.delay_ms.map(Duration::from_millis);
    let mut session = Session::new(shared, transports);
    let mut chunk = vec![0u8; 16 * 1024];
    let mut last = Instant::now();
    'conn: while !stop.load(Ordering::SeqCst) && !slot.evict.load(Ordering::SeqCst) {
        match stream.read(&mut chunk) {
            Ok(0) => break,
            Ok(n) => {
                if chunk[..n].iter().any(|b| !b.is_ascii_whitespace()) {
                    last = Instant::now();
                }
                let out = session.feed(&chunk[..n]);
                if !out.messages.is_empty() {
                    slot.progress_ms.store(start.elapsed().as_millis() as u64, Ordering::SeqCst);
                }
                for m in &out.messages {
                    if let Some(d) = delay {
                        std::thread::sleep(d);
                    }
                    if stream.write_all(m).is_err() {
                        break 'conn;
                    }
                }
                if out.close {
                    break;
                }
            }
            Err(e) if matches!(e.kind(), std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut) => {
                if last.elapsed() >= idle {
                    break;
                }
            }
            Err(_) => break,
        }
    }
    // Motion is free before the peer can see the connection closed.
    drop(session);
    // Close our side, then read what the peer still sends for a moment (bounded): closing with
    // unread bytes would reset the connection and could lose the last answer (an error saying
    // why the connection closes).
    let _ = stream.shutdown(std::net::Shutdown::Write);
    let end = Instant::now() + Duration::from_millis(200);
    while Instant::now() < end && matches!(stream.read(&mut chunk), Ok(n) if n > 0) {}
}
