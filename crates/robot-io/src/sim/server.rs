//! The simulator's sockets: the listeners, at most [`SimOptions::max_connections`] connections
//! at once, and each connection closed after [`SimOptions::idle_timeout`] without a byte.
//!
//! [`SimOptions::max_connections`]: super::SimOptions::max_connections
//! [`SimOptions::idle_timeout`]: super::SimOptions::idle_timeout

use std::io::{Read, Write};
use std::net::{SocketAddr, TcpListener, TcpStream};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use super::Listen;
use super::dispatch::Shared;
use super::session::Session;
use crate::RobotError;
use crate::wire::Transport;

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
        while !stop.load(Ordering::SeqCst) {
            let mut idle = true;
            for (listener, transports) in &listeners {
                let Ok((stream, _)) = listener.accept() else { continue };
                idle = false;
                // Over the limit: closed at once (dropping the stream), nothing read.
                if shared.connections.load(Ordering::SeqCst) >= shared.options.max_connections {
                    continue;
                }
                shared.connections.fetch_add(1, Ordering::SeqCst);
                let (shared, stop, transports) = (shared.clone(), stop.clone(), transports.clone());
                std::thread::spawn(move || {
                    serve(stream, &transports, &shared, &stop);
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

/// Serves one connection until the peer closes it, it stays idle too long, the session closes
/// it, or the simulator stops.
fn serve(mut stream: TcpStream, transports: &[Transport], shared: &Shared, stop: &AtomicBool) {
    let idle = shared.options.idle_timeout;
    let _ = stream.set_read_timeout(Some(Duration::from_millis(50)));
    // A peer that does not read its answers cannot hold the thread longer than this.
    let _ = stream.set_write_timeout(Some(idle));
    let _ = stream.set_nodelay(true);
    let delay = shared.options.faults.delay_ms.map(Duration::from_millis);
    let mut session = Session::new(shared, transports);
    let mut chunk = vec![0u8; 16 * 1024];
    let mut last = Instant::now();
    'conn: while !stop.load(Ordering::SeqCst) {
        match stream.read(&mut chunk) {
            Ok(0) => break,
            Ok(n) => {
                last = Instant::now();
                let out = session.feed(&chunk[..n]);
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
