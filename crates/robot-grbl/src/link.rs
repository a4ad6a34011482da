//! The byte link to the machine: a serial device (USB serial, or any character device such as a
//! pseudo-terminal) or a TCP socket (a GRBL board bridged over the network), read in lines of
//! bounded length.

use std::io::{self, Read, Write};
use std::net::TcpStream;
use std::time::{Duration, Instant};

use crate::GrblError;

/// The longest line read from the machine, bytes. GRBL 1.1's longest lines (a `$N` startup
/// line, a `[GC:…]` report) are under 100 bytes; a longer one is not GRBL speaking.
pub const MAX_LINE_BYTES: usize = 256;

/// A byte link to a GRBL controller.
pub trait Port: Send {
    /// Reads what is there, waiting at most `timeout`; `Ok(0)` when nothing came.
    ///
    /// # Errors
    /// The I/O error; a closed link is [`io::ErrorKind::UnexpectedEof`].
    fn read_some(&mut self, buf: &mut [u8], timeout: Duration) -> io::Result<usize>;

    /// Writes every byte (within the link's write time-out).
    ///
    /// # Errors
    /// The I/O error (a link that takes nothing for the time-out is
    /// [`io::ErrorKind::TimedOut`]).
    fn write_all_bytes(&mut self, bytes: &[u8]) -> io::Result<()>;
}

/// How long a write may wait for the link to take its bytes.
const WRITE_TIMEOUT: Duration = Duration::from_secs(5);

/// A serial device opened with `serialport` (8N1, no flow control, raw).
pub struct SerialLink {
    port: Box<dyn serialport::SerialPort>,
}

impl SerialLink {
    /// Opens `path` at `baud` (GRBL 1.1: 115200). Opening an Arduino's port usually resets the
    /// board, which then prints its banner.
    ///
    /// # Errors
    /// [`GrblError::Io`] naming the device.
    pub fn open(path: &str, baud: u32) -> Result<SerialLink, GrblError> {
        let port = serialport::new(path, baud)
            .timeout(WRITE_TIMEOUT)
            .open()
            .map_err(|e| GrblError::Io { context: format!("opening {path} at {baud} baud"), source: e.into() })?;
        Ok(SerialLink { port })
    }
}

impl Port for SerialLink {
    fn read_some(&mut self, buf: &mut [u8], timeout: Duration) -> io::Result<usize> {
        self.port.set_timeout(timeout.max(Duration::from_millis(1))).map_err(io::Error::from)?;
        match self.port.read(buf) {
            Ok(0) => Err(io::ErrorKind::UnexpectedEof.into()),
            Ok(n) => Ok(n),
            Err(e) if e.kind() == io::ErrorKind::TimedOut || e.kind() == io::ErrorKind::WouldBlock => Ok(0),
            // A pseudo-terminal whose other side closed, or a USB device unplugged.
            Err(e) if e.raw_os_error() == Some(5) => Err(io::Error::new(io::ErrorKind::UnexpectedEof, e)),
            Err(e) => Err(e),
        }
    }

    fn write_all_bytes(&mut self, bytes: &[u8]) -> io::Result<()> {
        self.port.set_timeout(WRITE_TIMEOUT).map_err(io::Error::from)?;
        self.port.write_all(bytes)?;
        self.port.flush()
    }
}

/// A TCP socket to a serial bridge (ESP8266/ESP32 boards, `ser2net`), bytes passed as they are.
pub struct TcpLink {
    stream: TcpStream,
}

impl TcpLink {
    /// Connects to `addr` (`HOST:PORT`) within `timeout`.
    ///
    /// # Errors
    /// [`GrblError::Io`] naming the address.
    pub fn connect(addr: &str, timeout: Duration) -> Result<TcpLink, GrblError> {
        use std::net::ToSocketAddrs;
        let io_err = |source| GrblError::Io { context: format!("connecting to {addr}"), source };
        let mut last = io::Error::new(io::ErrorKind::NotFound, "the address resolves to nothing");
        for a in addr.to_socket_addrs().map_err(io_err)? {
            match TcpStream::connect_timeout(&a, timeout) {
                Ok(stream) => {
                    stream.set_nodelay(true).map_err(io_err)?;
                    stream.set_write_timeout(Some(WRITE_TIMEOUT)).map_err(io_err)?;
                    return Ok(TcpLink { stream });
                }
                Err(e) => last = e,
            }
        }
        Err(io_err(last))
    }
}

impl Port for TcpLink {
    fn read_some(&mut self, buf: &mut [u8], timeout: Duration) -> io::Result<usize> {
        self.stream.set_read_timeout(Some(timeout.max(Duration::from_millis(1))))?;
        match self.stream.read(buf) {
            Ok(0) => Err(io::ErrorKind::UnexpectedEof.into()),
            Ok(n) => Ok(n),
            Err(e) if e.kind() == io::ErrorKind::TimedOut || e.kind() == io::ErrorKind::WouldBlock => Ok(0),
            Err(e) => Err(e),
        }
    }

    fn write_all_bytes(&mut self, bytes: &[u8]) -> io::Result<()> {
        self.stream.write_all(bytes)?;
        self.stream.flush()
    }
}

/// Lines from a [`Port`]: `\n`-terminated (a `\r` before it dropped), at most
/// [`MAX_LINE_BYTES`] each.
pub(crate) struct Lines {
    port: Box<dyn Port>,
    buf: Vec<u8>,
    /// Where a line starts in `buf` (bytes before it were returned).
    start: usize,
    /// Set when the link closed or failed: every later read fails the same way.
    closed: Option<io::ErrorKind>,
}

impl Lines {
    pub(crate) fn new(port: Box<dyn Port>) -> Lines {
        Lines { port, buf: Vec::with_capacity(2 * MAX_LINE_BYTES), start: 0, closed: None }
    }

    /// The next line, or `None` when none is complete by `deadline`.
    pub(crate) fn next_line(&mut self, deadline: Instant) -> Result<Option<String>, GrblError> {
        loop {
            if let Some(i) = self.buf[self.start..].iter().position(|&b| b == b'\n') {
                let end = self.start + i;
                let mut line = &self.buf[self.start..end];
                if line.last() == Some(&b'\r') {
                    line = &line[..line.len() - 1];
                }
                // GRBL speaks ASCII; anything else is shown, not trusted.
                let text = String::from_utf8_lossy(line).into_owned();
                self.start = end + 1;
                return Ok(Some(text));
            }
            if self.buf.len() - self.start > MAX_LINE_BYTES {
                return Err(GrblError::Protocol(format!(
                    "a line longer than {MAX_LINE_BYTES} bytes came from the controller: not GRBL's protocol (wrong baud rate?)"
                )));
            }
            if let Some(kind) = self.closed {
                return Err(GrblError::Io { context: "reading from the controller".into(), source: kind.into() });
            }
            // Keep the buffer small: drop what was returned.
            if self.start > 0 {
                self.buf.drain(..self.start);
                self.start = 0;
            }
            let now = Instant::now();
            if now >= deadline {
                return Ok(None);
            }
            let mut chunk = [0u8; 256];
            match self.port.read_some(&mut chunk, deadline - now) {
                Ok(0) => {}
                Ok(n) => self.buf.extend_from_slice(&chunk[..n]),
                Err(e) => {
                    self.closed = Some(e.kind());
                    return Err(GrblError::Io { context: "reading from the controller".into(), source: e });
                }
            }
        }
    }

    pub(crate) fn write(&mut self, bytes: &[u8]) -> Result<(), GrblError> {
        if let Some(kind) = self.closed {
            return Err(GrblError::Io { context: "writing to the controller".into(), source: kind.into() });
        }
        self.port.write_all_bytes(bytes).map_err(|e| {
            self.closed = Some(e.kind());
            GrblError::Io { context: "writing to the controller".into(), source: e }
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::VecDeque;

    /// A port that gives its chunks one read at a time, then nothing, or a closed link.
    struct Script(VecDeque<Vec<u8>>, bool);

    impl Port for Script {
        fn read_some(&mut self, buf: &mut [u8], _timeout: Duration) -> io::Result<usize> {
            match self.0.pop_front() {
                Some(c) => {
                    buf[..c.len()].copy_from_slice(&c);
                    Ok(c.len())
                }
                None if self.1 => Err(io::ErrorKind::UnexpectedEof.into()),
                None => Ok(0),
            }
        }
        fn write_all_bytes(&mut self, _: &[u8]) -> io::Result<()> {
            Ok(())
        }
    }

    #[test]
    fn lines_are_split_bounded_and_a_closed_link_stays_closed() {
        let chunks = [b"o".to_vec(), b"k\r\nerr".to_vec(), b"or:9\r\n".to_vec()];
        let mut l = Lines::new(Box::new(Script(chunks.into_iter().collect(), true)));
        let soon = Instant::now() + Duration::from_secs(1);
        assert_eq!(l.next_line(soon).unwrap().as_deref(), Some("ok"));
        assert_eq!(l.next_line(soon).unwrap().as_deref(), Some("error:9"));
        assert!(matches!(l.next_line(soon), Err(GrblError::Io { .. })));
        assert!(matches!(l.next_line(soon), Err(GrblError::Io { .. })));
        // Noise without a line end is refused once it exceeds the bound, not kept.
        let noise = vec![vec![b'x'; 200], vec![b'x'; 200]];
        let mut l = Lines::new(Box::new(Script(noise.into_iter().collect(), false)));
        assert!(matches!(l.next_line(soon), Err(GrblError::Protocol(_))));
        // Nothing: `None` at the deadline.
        let mut l = Lines::new(Box::new(Script(VecDeque::new(), false)));
        assert_eq!(l.next_line(Instant::now()).unwrap(), None);
    }
}
