//! The UR dashboard server (port 29999): one line in, one line out. On connection the server
//! greets with a line ("Connected: Universal Robots Dashboard Server"); maobi uses `stop`
//! ("Stopped"), `programState` ("STOPPED name", "PLAYING name"), `robotmode` ("Robotmode:
//! RUNNING"), `safetystatus` ("Safetystatus: NORMAL"), `PolyscopeVersion` ("URSoftware 5.x …")
//! and `is in remote control` ("true"), as UR's client library sends and expects them
//! (`src/ur/dashboard_client_implementation_g5.cpp`).

use std::io::{Read, Write};
use std::net::TcpStream;
use std::time::{Duration, Instant};

use super::rtde::{connect_stream, io_error};
use crate::RobotError;

/// The longest line the client reads from the dashboard server, bytes.
pub const MAX_DASHBOARD_LINE_BYTES: usize = 4096;

/// A connection to the dashboard server.
pub struct Dashboard {
    stream: TcpStream,
    buf: Vec<u8>,
    timeout: Duration,
    addr: String,
    /// The server's greeting.
    pub greeting: String,
}

impl Dashboard {
    /// Connects and reads the greeting.
    ///
    /// # Errors
    /// [`RobotError::Io`], [`RobotError::Timeout`]; [`RobotError::Protocol`] for a line longer
    /// than [`MAX_DASHBOARD_LINE_BYTES`] or not UTF-8.
    pub fn connect(addr: &str, timeout: Duration) -> Result<Self, RobotError> {
        let stream = connect_stream(addr, timeout)?;
        let mut d = Dashboard { stream, buf: Vec::new(), timeout, addr: addr.to_string(), greeting: String::new() };
        d.greeting = d.line("the dashboard greeting")?;
        Ok(d)
    }

    /// Sends `command` (one line) and returns the answer line, trimmed.
    ///
    /// # Errors
    /// [`RobotError::Protocol`] for a command with a line end or a control character (it would
    /// be two commands); as [`Dashboard::connect`].
    pub fn command(&mut self, command: &str) -> Result<String, RobotError> {
        if command.chars().any(char::is_control) {
            return Err(RobotError::Protocol(format!("dashboard command {command:?} has a control character")));
        }
        let what = format!("dashboard `{command}` at {}", self.addr);
        self.stream.write_all(format!("{command}\n").as_bytes()).map_err(|e| io_error(&what, e))?;
        self.line(&what)
    }

    /// The next line, without its line end.
    fn line(&mut self, what: &str) -> Result<String, RobotError> {
        let deadline = Instant::now() + self.timeout;
        loop {
            if let Some(i) = self.buf.iter().position(|&b| b == b'\n') {
                let line: Vec<u8> = self.buf.drain(..=i).collect();
                let text = String::from_utf8(line)
                    .map_err(|_| RobotError::Protocol(format!("{what}: the answer is not UTF-8")))?;
                return Ok(text.trim_end().to_string());
            }
            if self.buf.len() > MAX_DASHBOARD_LINE_BYTES {
                return Err(RobotError::Protocol(format!(
                    "{what}: an answer longer than {MAX_DASHBOARD_LINE_BYTES} bytes"
                )));
            }
            let now = Instant::now();
            if now >= deadline {
                return Err(RobotError::Timeout(what.to_string()));
            }
            self.stream.set_read_timeout(Some(deadline - now)).map_err(|e| io_error(what, e))?;
            let mut chunk = [0u8; 1024];
            match self.stream.read(&mut chunk) {
                Ok(0) => {
                    let e =
                        std::io::Error::new(std::io::ErrorKind::UnexpectedEof, "connection closed by the controller");
                    return Err(io_error(what, e));
                }
                Ok(n) => self.buf.extend_from_slice(&chunk[..n]),
                Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
                Err(e) => return Err(io_error(what, e)),
            }
        }
    }
}
