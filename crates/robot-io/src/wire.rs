//! The AUBO controller's wire formats, as the official SDK (`pyaubo-sdk` 0.24.1) speaks them:
//! the framed transport (`SOF`, a type byte, a big-endian length, the payload), the SDK's JSON
//! text (keys sorted, numbers as its JSON library prints them), the login message and its
//! password digest; and the two other forms maobi speaks: line-delimited JSON values and
//! JSON-RPC over HTTP/1.1. See docs/robot.md ("AUBO interfaces") for the protocol table.

use std::fmt::Write as _;

use serde_json::Value;

use crate::RobotError;

/// The magic every frame starts with.
pub const MAGIC: &[u8; 3] = b"SOF";
/// Frame type with a 4-byte length: the only type the SDK sends.
pub const TYPE_LONG: u8 = 1;
/// Frame type with a 2-byte length: accepted from a peer, never sent.
pub const TYPE_SHORT: u8 = 0;
/// Largest payload accepted in one frame (and one HTTP body), bytes: 8 MiB.
pub const MAX_FRAME_BYTES: usize = 8 << 20;
/// Largest HTTP head (request or status line and headers) accepted, bytes.
pub const MAX_HTTP_HEAD_BYTES: usize = 16 << 10;
/// The JSON-RPC over HTTP port AUBO documents.
pub const HTTP_PORT: u16 = 9012;
/// The controller's JSON-RPC port (framed and line-delimited).
pub const RPC_PORT: u16 = 30004;
/// The controller's script port.
pub const SCRIPT_PORT: u16 = 30002;
/// The path maobi posts JSON-RPC requests to (an assumption; the simulator accepts any path).
pub const HTTP_PATH: &str = "/jsonrpc";
/// `SystemInfo.getInterfaceVersionCode` of the interface maobi speaks (SDK 0.24.0).
pub const INTERFACE_VERSION: i64 = 24000;
/// The SDK version sent in the login message.
pub const SDK_VERSION: &str = "0.24.0";
/// The controller's default user.
pub const DEFAULT_USER: &str = "aubo";
/// The controller's default password.
pub const DEFAULT_PASSWORD: &str = "123456";

/// How requests and answers travel on the connection.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Transport {
    /// The SDK's framed protocol on the RPC port (30004): named params, string ids, login.
    #[default]
    Framed,
    /// One JSON value after another on the RPC port, positional params, integer ids, no login
    /// (maobi's earlier form, kept as `--transport lines`).
    Lines,
    /// JSON-RPC 2.0 over HTTP/1.1 POST (port 9012): named params, string ids, no login.
    Http,
}

impl Transport {
    /// All transports, in the order the CLI lists them.
    pub const ALL: [Transport; 3] = [Transport::Framed, Transport::Lines, Transport::Http];

    /// The name used on the command line: `framed`, `lines` or `http`.
    pub fn name(self) -> &'static str {
        match self {
            Transport::Framed => "framed",
            Transport::Lines => "lines",
            Transport::Http => "http",
        }
    }

    /// The controller's port for this transport: 30004 (framed, lines) or 9012 (HTTP).
    pub fn default_port(self) -> u16 {
        match self {
            Transport::Framed | Transport::Lines => RPC_PORT,
            Transport::Http => HTTP_PORT,
        }
    }

    /// Whether params go as a named object (framed, HTTP) rather than a positional array.
    pub fn named_params(self) -> bool {
        !matches!(self, Transport::Lines)
    }
}

impl std::fmt::Display for Transport {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for Transport {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        Transport::ALL
            .into_iter()
            .find(|t| t.name() == s)
            .ok_or_else(|| format!("unknown transport `{s}`: expected framed, lines or http"))
    }
}

/// One frame of type 1 (`SOF`, 0x01, the payload length as 4 bytes big-endian, the payload),
/// ready to be written in one piece.
///
/// # Errors
/// [`RobotError::Framing`] if the payload is longer than [`MAX_FRAME_BYTES`].
pub fn encode_frame(payload: &[u8]) -> Result<Vec<u8>, RobotError> {
    if payload.len() > MAX_FRAME_BYTES {
        return Err(RobotError::Framing(format!(
            "payload of {} bytes exceeds the frame limit of {MAX_FRAME_BYTES} bytes",
            payload.len()
        )));
    }
    let mut out = Vec::with_capacity(payload.len() + 8);
    out.extend_from_slice(MAGIC);
    out.push(TYPE_LONG);
    out.extend_from_slice(&(payload.len() as u32).to_be_bytes());
    out.extend_from_slice(payload);
    Ok(out)
}

/// Splits a byte stream into frame payloads; bytes may arrive in any pieces.
#[derive(Debug)]
pub struct FrameDecoder {
    buf: Vec<u8>,
    limit: usize,
}

impl Default for FrameDecoder {
    fn default() -> Self {
        Self::new(MAX_FRAME_BYTES)
    }
}

impl FrameDecoder {
    /// A decoder that refuses payloads longer than `limit` bytes.
    pub fn new(limit: usize) -> Self {
        Self { buf: Vec::new(), limit }
    }

    /// Appends bytes read from the stream.
    pub fn push(&mut self, bytes: &[u8]) {
        self.buf.extend_from_slice(bytes);
    }

    /// Bytes held that do not yet make a whole frame.
    pub fn pending(&self) -> usize {
        self.buf.len()
    }

    /// Whether the bytes held start like a frame (`SOF`, or a prefix of it): false once the
    /// stream is not in the framed format at all, so an error frame would not be understood.
    pub fn in_sync(&self) -> bool {
        let n = self.buf.len().min(3);
        self.buf[..n] == MAGIC[..n]
    }

    /// The next whole frame's payload, or `None` until more bytes arrive.
    ///
    /// # Errors
    /// [`RobotError::Framing`] when the bytes do not start with `SOF`, the type is neither 0 nor
    /// 1, or the length exceeds the limit; the stream cannot be resynchronised after that.
    pub fn next_frame(&mut self) -> Result<Option<Vec<u8>>, RobotError> {
        let have = self.buf.len();
        let magic = &self.buf[..have.min(3)];
        if magic != &MAGIC[..magic.len()] {
            return Err(RobotError::Framing(format!(
                "expected a frame starting with \"SOF\", got {}",
                show_bytes(&self.buf[..have.min(8)])
            )));
        }
        if have < 4 {
            return Ok(None);
        }
        let len_bytes = match self.buf[3] {
            TYPE_LONG => 4,
            TYPE_SHORT => 2,
            t => {
                return Err(RobotError::Framing(format!(
                    "frame type {t}: expected 0 (2-byte length) or 1 (4-byte length)"
                )));
            }
        };
        if have < 4 + len_bytes {
            return Ok(None);
        }
        let len = self.buf[4..4 + len_bytes].iter().fold(0usize, |n, &b| (n << 8) | usize::from(b));
        if len > self.limit {
            return Err(RobotError::Framing(format!(
                "frame length {len} bytes exceeds the limit of {} bytes",
                self.limit
            )));
        }
        let total = 4 + len_bytes + len;
        if have < total {
            return Ok(None);
        }
        let payload = self.buf[4 + len_bytes..total].to_vec();
        self.buf.drain(..total);
        Ok(Some(payload))
    }

    /// Says what is missing when the stream ends now: `None` if nothing is pending.
    pub fn incomplete(&self) -> Option<String> {
        if self.buf.is_empty() {
            return None;
        }
        let want = match self.buf.get(3) {
            Some(&TYPE_SHORT) if self.buf.len() >= 6 => {
                Some(6 + usize::from(u16::from_be_bytes([self.buf[4], self.buf[5]])))
            }
            Some(&TYPE_LONG) if self.buf.len() >= 8 => {
                Some(8 + u32::from_be_bytes([self.buf[4], self.buf[5], self.buf[6], self.buf[7]]) as usize)
            }
            _ => None,
        };
        Some(match want {
            Some(n) => format!("the connection closed in the middle of a frame ({} of {n} bytes)", self.buf.len()),
            None => format!("the connection closed in the middle of a frame header ({} bytes)", self.buf.len()),
        })
    }
}

/// Up to the first bytes, printable as text where they are ASCII.
pub(crate) fn show_bytes(b: &[u8]) -> String {
    format!("{:?}", String::from_utf8_lossy(b))
}

/// The login payload the SDK sends: `__login__\n<user>\n<digest>\n0.24.0\n`.
///
/// # Errors
/// [`RobotError::Login`] if the user name is empty or contains a newline (it would break the
/// message).
pub fn login_payload(user: &str, password: &str) -> Result<Vec<u8>, RobotError> {
    if user.is_empty() || user.contains(['\n', '\r']) {
        return Err(RobotError::Login {
            user: user.to_string(),
            message: "the user name must be non-empty and on one line".into(),
        });
    }
    Ok(format!("__login__\n{user}\n{}\n{SDK_VERSION}\n", login_digest(password)).into_bytes())
}

/// The digits the SDK sends before the password's, found by capture (constant for every user
/// and password).
const DIGEST_HEAD: &str = "33535454353536643454";
/// The digits the SDK sends after the password's.
const DIGEST_TAIL: &str = "43435463466335333566235443434253142434333426365553";

/// The password digest of the SDK's login message, as worked out from its traffic (black box,
/// see `tests/golden/`): a fixed 20-digit head, then for every byte of the password's UTF-8 the
/// number of its set bits (one decimal digit, 0–8), then a fixed 50-digit tail. It does not
/// depend on the user. (It is not a cryptographic hash: many passwords share a digest.)
pub fn login_digest(password: &str) -> String {
    let mut s = String::with_capacity(DIGEST_HEAD.len() + password.len() + DIGEST_TAIL.len());
    s.push_str(DIGEST_HEAD);
    for b in password.bytes() {
        s.push(char::from(b'0' + b.count_ones() as u8));
    }
    s.push_str(DIGEST_TAIL);
    s
}

/// A parsed login message (what the simulator receives).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct LoginRequest {
    /// The user.
    pub user: String,
    /// The password digest ([`login_digest`]).
    pub digest: String,
    /// The client's SDK version.
    pub version: String,
}

/// Parses a login payload; `None` if it is not one.
pub fn parse_login(payload: &[u8]) -> Option<LoginRequest> {
    let text = std::str::from_utf8(payload).ok()?;
    let rest = text.strip_prefix("__login__\n")?;
    let mut parts = rest.split('\n');
    let user = parts.next()?.to_string();
    let digest = parts.next()?.to_string();
    let version = parts.next().unwrap_or("").to_string();
    Some(LoginRequest { user, digest, version })
}

/// The login answer: `__login__\nSUCCEED` or `__login__\nFAILED`.
pub fn login_reply(ok: bool) -> Vec<u8> {
    format!("__login__\n{}", if ok { "SUCCEED" } else { "FAILED" }).into_bytes()
}

/// JSON text as the SDK writes it: no spaces, object keys in byte order, numbers as its JSON
/// library prints doubles (shortest digits; `0.0`, `24000.0`, `0.0005`, `1e-05`, `1.5e+16`),
/// non-ASCII text as UTF-8, control characters escaped; non-finite numbers as `null`.
pub fn sdk_json(v: &Value) -> String {
    let mut s = String::new();
    write_json(v, &mut s);
    s
}

fn write_json(v: &Value, out: &mut String) {
    match v {
        Value::Null => out.push_str("null"),
        Value::Bool(b) => out.push_str(if *b { "true" } else { "false" }),
        Value::Number(n) => {
            if let Some(i) = n.as_i64() {
                let _ = write!(out, "{i}");
            } else if let Some(u) = n.as_u64() {
                let _ = write!(out, "{u}");
            } else {
                write_f64(n.as_f64().unwrap_or(f64::NAN), out);
            }
        }
        Value::String(s) => write_str(s, out),
        Value::Array(a) => {
            out.push('[');
            for (i, x) in a.iter().enumerate() {
                if i > 0 {
                    out.push(',');
                }
                write_json(x, out);
            }
            out.push(']');
        }
        Value::Object(m) => {
            let mut keys: Vec<&String> = m.keys().collect();
            keys.sort();
            out.push('{');
            for (i, k) in keys.into_iter().enumerate() {
                if i > 0 {
                    out.push(',');
                }
                write_str(k, out);
                out.push(':');
                write_json(&m[k.as_str()], out);
            }
            out.push('}');
        }
    }
}

fn write_str(s: &str, out: &mut String) {
    out.push('"');
    for c in s.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            '\u{8}' => out.push_str("\\b"),
            '\u{c}' => out.push_str("\\f"),
            '\n' => out.push_str("\\n"),
            '\r' => out.push_str("\\r"),
            '\t' => out.push_str("\\t"),
            c if (c as u32) < 0x20 => {
                let _ = write!(out, "\\u{:04x}", c as u32);
            }
            c => out.push(c),
        }
    }
    out.push('"');
}

/// A double as the SDK's JSON library prints it: the shortest digits that read back exactly;
/// plain notation when the decimal point falls within 15 digits to the right of the first digit
/// or 3 zeros to its left (`0.0005`), otherwise `d.ddde±XX` with at least two exponent digits;
/// always a `.` or an exponent, so the text reads back as a double.
pub fn write_f64(x: f64, out: &mut String) {
    if !x.is_finite() {
        out.push_str("null");
        return;
    }
    if x.is_sign_negative() {
        out.push('-');
    }
    if x == 0.0 {
        out.push_str("0.0");
        return;
    }
    // Rust's `{:e}` gives the shortest round-trip digits: "d.ddddde-7".
    let e_form = format!("{:e}", x.abs());
    let (mant, exp) = e_form.split_once('e').unwrap_or((&e_form, "0"));
    let digits: String = mant.chars().filter(char::is_ascii_digit).collect();
    let exp: i32 = exp.parse().unwrap_or(0);
    let k = digits.len() as i32;
    let n = exp + 1; // the decimal point's position after the first digit
    const MIN_EXP: i32 = -4;
    const MAX_EXP: i32 = 15;
    if k <= n && n <= MAX_EXP {
        out.push_str(&digits);
        out.extend(std::iter::repeat_n('0', (n - k) as usize));
        out.push_str(".0");
    } else if 0 < n && n <= MAX_EXP {
        out.push_str(&digits[..n as usize]);
        out.push('.');
        out.push_str(&digits[n as usize..]);
    } else if MIN_EXP < n && n <= 0 {
        out.push_str("0.");
        out.extend(std::iter::repeat_n('0', (-n) as usize));
        out.push_str(&digits);
    } else {
        out.push_str(&digits[..1]);
        if k > 1 {
            out.push('.');
            out.push_str(&digits[1..]);
        }
        let e = n - 1;
        let _ = write!(out, "e{}{:02}", if e < 0 { '-' } else { '+' }, e.abs());
    }
}

/// An HTTP/1.1 message head: the start line and the headers (names in lower case).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct HttpHead {
    /// `POST /jsonrpc HTTP/1.1` or `HTTP/1.1 200 OK`.
    pub start: String,
    /// Header names (lower case) and values.
    pub headers: Vec<(String, String)>,
}

impl HttpHead {
    /// The first header called `name` (lower case).
    pub fn header(&self, name: &str) -> Option<&str> {
        self.headers.iter().find(|(k, _)| k == name).map(|(_, v)| v.as_str())
    }
}

/// Parses an HTTP/1.1 head (without its blank line): the start line, the headers and the
/// body length its `Content-Length` states (`None` without one).
///
/// # Errors
/// [`RobotError::Framing`] for a head that is not UTF-8, a malformed header line, chunked
/// transfer coding, a `Content-Length` that is not a number, or two `Content-Length` headers
/// that disagree (the message could be read two ways; identical repeats are accepted).
pub fn parse_http_head(head: &[u8]) -> Result<(HttpHead, Option<usize>), RobotError> {
    let text = std::str::from_utf8(head).map_err(|_| RobotError::Framing("HTTP head is not UTF-8".into()))?;
    let mut lines = text.split("\r\n");
    let start = lines.next().unwrap_or("").to_string();
    let mut headers = Vec::new();
    for l in lines {
        let (k, v) =
            l.split_once(':').ok_or_else(|| RobotError::Framing(format!("malformed HTTP header line {l:?}")))?;
        headers.push((k.trim().to_ascii_lowercase(), v.trim().to_string()));
    }
    let head = HttpHead { start, headers };
    if head.header("transfer-encoding").is_some_and(|v| !v.eq_ignore_ascii_case("identity")) {
        return Err(RobotError::Framing("chunked HTTP bodies are not supported: send Content-Length".into()));
    }
    let mut len = None;
    for (_, v) in head.headers.iter().filter(|(k, _)| k == "content-length") {
        let n = v.parse::<usize>().map_err(|_| RobotError::Framing(format!("Content-Length {v:?} is not a number")))?;
        if len.is_some_and(|l| l != n) {
            return Err(RobotError::Framing(format!(
                "two Content-Length headers that disagree ({} and {n} bytes)",
                len.unwrap_or_default()
            )));
        }
        len = Some(n);
    }
    Ok((head, len))
}

/// Takes one HTTP/1.1 message (head and a `Content-Length` body) off the front of `buf`, or
/// `None` until it is complete.
///
/// # Errors
/// [`RobotError::Framing`] for a head over [`MAX_HTTP_HEAD_BYTES`] or one [`parse_http_head`]
/// refuses, a missing `Content-Length` when `need_length` is set, or a body over
/// [`MAX_FRAME_BYTES`].
pub fn take_http_message(buf: &mut Vec<u8>, need_length: bool) -> Result<Option<(HttpHead, Vec<u8>)>, RobotError> {
    let Some(end) = buf.windows(4).position(|w| w == b"\r\n\r\n") else {
        if buf.len() > MAX_HTTP_HEAD_BYTES {
            return Err(RobotError::Framing(format!("HTTP head longer than {MAX_HTTP_HEAD_BYTES} bytes")));
        }
        return Ok(None);
    };
    if end > MAX_HTTP_HEAD_BYTES {
        return Err(RobotError::Framing(format!("HTTP head longer than {MAX_HTTP_HEAD_BYTES} bytes")));
    }
    let (head, len) = parse_http_head(&buf[..end])?;
    let len = match len {
        Some(n) => n,
        None if need_length => return Err(RobotError::Framing("HTTP message without Content-Length".into())),
        None => 0,
    };
    if len > MAX_FRAME_BYTES {
        return Err(RobotError::Framing(format!(
            "HTTP body of {len} bytes exceeds the limit of {MAX_FRAME_BYTES} bytes"
        )));
    }
    let total = end + 4 + len;
    if buf.len() < total {
        return Ok(None);
    }
    let body = buf[end + 4..total].to_vec();
    buf.drain(..total);
    Ok(Some((head, body)))
}

/// Splits a byte stream into HTTP/1.1 requests, scanning every byte once: the search for the
/// end of a head resumes where the last one stopped, so a head or a body arriving in many small
/// pieces costs time in proportion to its length. Bodies longer than the limit, and heads
/// longer than [`MAX_HTTP_HEAD_BYTES`], are refused before they are buffered.
#[derive(Debug)]
pub struct HttpDecoder {
    buf: Vec<u8>,
    scanned: usize,
    head: Option<(HttpHead, Option<usize>, usize)>,
    limit: usize,
}

impl HttpDecoder {
    /// A decoder that refuses bodies longer than `limit_bytes`.
    pub fn new(limit_bytes: usize) -> Self {
        Self { buf: Vec::new(), scanned: 0, head: None, limit: limit_bytes }
    }

    /// Appends bytes read from the stream.
    pub fn push(&mut self, bytes: &[u8]) {
        self.buf.extend_from_slice(bytes);
    }

    /// Bytes held that do not yet make a whole message.
    pub fn pending(&self) -> usize {
        self.buf.len()
    }

    /// The next whole request: its head and its body (empty when the head states no
    /// `Content-Length`; [`HttpHead::header`] tells the two apart), or `None` until more bytes
    /// arrive.
    ///
    /// # Errors
    /// [`RobotError::Framing`] for a head over [`MAX_HTTP_HEAD_BYTES`] or one
    /// [`parse_http_head`] refuses, or a body over the limit; the stream cannot be used after
    /// that.
    pub fn next_message(&mut self) -> Result<Option<(HttpHead, Vec<u8>)>, RobotError> {
        if self.head.is_none() {
            let from = self.scanned.saturating_sub(3);
            let Some(at) = self.buf[from..].windows(4).position(|w| w == b"\r\n\r\n") else {
                self.scanned = self.buf.len();
                if self.buf.len() > MAX_HTTP_HEAD_BYTES {
                    return Err(RobotError::Framing(format!("HTTP head longer than {MAX_HTTP_HEAD_BYTES} bytes")));
                }
                return Ok(None);
            };
            let end = from + at;
            if end > MAX_HTTP_HEAD_BYTES {
                return Err(RobotError::Framing(format!("HTTP head longer than {MAX_HTTP_HEAD_BYTES} bytes")));
            }
            let (head, len) = parse_http_head(&self.buf[..end])?;
            if len.is_some_and(|n| n > self.limit) {
                return Err(RobotError::Framing(format!(
                    "HTTP body of {} bytes exceeds the limit of {} bytes",
                    len.unwrap_or_default(),
                    self.limit
                )));
            }
            self.head = Some((head, len, end + 4));
        }
        let Some((_, len, body_at)) = &self.head else { return Ok(None) };
        let total = body_at + len.unwrap_or(0);
        if self.buf.len() < total {
            return Ok(None);
        }
        let body = self.buf[*body_at..total].to_vec();
        self.buf.drain(..total);
        self.scanned = 0;
        Ok(self.head.take().map(|(h, _, _)| (h, body)))
    }
}

/// Splits a byte stream into JSON texts, each an object or an array (the line-delimited
/// transport: whitespace, newlines included, may separate them), scanning every byte once: the
/// scan of an unfinished text resumes where it stopped, so a text arriving in many small pieces
/// costs time in proportion to its length. A text longer than the limit is refused before it
/// is buffered whole.
#[derive(Debug)]
pub struct JsonTextDecoder {
    buf: Vec<u8>,
    scanned: usize,
    depth: usize,
    in_string: bool,
    escaped: bool,
    limit: usize,
}

impl JsonTextDecoder {
    /// A decoder that refuses texts longer than `limit_bytes`.
    pub fn new(limit_bytes: usize) -> Self {
        Self { buf: Vec::new(), scanned: 0, depth: 0, in_string: false, escaped: false, limit: limit_bytes }
    }

    /// Appends bytes read from the stream; whitespace between texts is dropped as it arrives.
    pub fn push(&mut self, bytes: &[u8]) {
        let bytes = if self.buf.is_empty() {
            let skip = bytes.iter().position(|b| !b.is_ascii_whitespace()).unwrap_or(bytes.len());
            &bytes[skip..]
        } else {
            bytes
        };
        self.buf.extend_from_slice(bytes);
    }

    /// Bytes held that do not yet make a whole text.
    pub fn pending(&self) -> usize {
        self.buf.len()
    }

    /// The next whole text's bytes (not yet parsed: brackets and strings balance, the JSON
    /// parser judges the rest), or `None` until more bytes arrive.
    ///
    /// # Errors
    /// [`RobotError::Framing`] when a text starts with something other than `{` or `[`, or
    /// grows past the limit; the stream cannot be used after that.
    pub fn next_text(&mut self) -> Result<Option<Vec<u8>>, RobotError> {
        let mut i = self.scanned;
        while i < self.buf.len() {
            let b = self.buf[i];
            if self.depth == 0 {
                // Between texts: only whitespace, then an object or an array.
                match b {
                    b if b.is_ascii_whitespace() => {
                        let n =
                            self.buf[i..].iter().position(|b| !b.is_ascii_whitespace()).unwrap_or(self.buf.len() - i);
                        self.buf.drain(..i + n);
                        i = 0;
                        continue;
                    }
                    b'{' | b'[' => self.depth = 1,
                    _ => {
                        return Err(RobotError::Framing(format!(
                            "expected a JSON object or array, got {}",
                            show_bytes(&self.buf[i..self.buf.len().min(i + 8)])
                        )));
                    }
                }
            } else if self.in_string {
                if self.escaped {
                    self.escaped = false;
                } else if b == b'\\' {
                    self.escaped = true;
                } else if b == b'"' {
                    self.in_string = false;
                }
            } else {
                match b {
                    b'"' => self.in_string = true,
                    b'{' | b'[' => self.depth += 1,
                    b'}' | b']' => {
                        self.depth -= 1;
                        if self.depth == 0 {
                            let text: Vec<u8> = self.buf.drain(..=i).collect();
                            self.scanned = 0;
                            return Ok(Some(text));
                        }
                    }
                    _ => {}
                }
            }
            i += 1;
            if i > self.limit {
                return Err(RobotError::Framing(format!("a JSON text longer than the limit of {} bytes", self.limit)));
            }
        }
        self.scanned = i;
        Ok(None)
    }
}

/// An HTTP/1.1 POST of a JSON body to [`HTTP_PATH`] on `host` (keep-alive).
pub fn http_post(host: &str, body: &[u8]) -> Vec<u8> {
    let mut out = format!(
        "POST {HTTP_PATH} HTTP/1.1\r\nHost: {host}\r\nContent-Type: application/json\r\nAccept: application/json\r\nContent-Length: {}\r\n\r\n",
        body.len()
    )
    .into_bytes();
    out.extend_from_slice(body);
    out
}

/// An HTTP/1.1 response with a JSON (or text) body.
pub fn http_response(status: u16, reason: &str, body: &[u8], close: bool) -> Vec<u8> {
    let mut out = format!(
        "HTTP/1.1 {status} {reason}\r\nContent-Type: application/json\r\nContent-Length: {}\r\nConnection: {}\r\n\r\n",
        body.len(),
        if close { "close" } else { "keep-alive" }
    )
    .into_bytes();
    out.extend_from_slice(body);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn f(x: f64) -> String {
        let mut s = String::new();
        write_f64(x, &mut s);
        s
    }

    #[test]
    fn doubles_print_as_the_sdk_prints_them() {
        for (x, want) in [
            (0.0, "0.0"),
            (-0.0, "-0.0"),
            (1.0, "1.0"),
            (24000.0, "24000.0"),
            (0.5, "0.5"),
            (0.0005, "0.0005"),
            (1e-5, "1e-05"),
            (1e-7, "1e-07"),
            (-1.25e-7, "-1.25e-07"),
            (std::f64::consts::PI, "3.141592653589793"),
            (123456789012345.0, "123456789012345.0"),
            (1234567890123456.0, "1.234567890123456e+15"),
            (1e16, "1e+16"),
            (1.5e300, "1.5e+300"),
            (f64::NAN, "null"),
        ] {
            assert_eq!(f(x), want, "{x:e}");
        }
    }

    #[test]
    fn objects_sort_their_keys_and_strings_escape_control_characters() {
        let v = serde_json::json!({"v": 0.5, "a": [1, -2, 0.25], "id": "x\"\n\u{1}中"});
        assert_eq!(sdk_json(&v), r#"{"a":[1,-2,0.25],"id":"x\"\n\u0001中","v":0.5}"#);
    }

    #[test]
    fn the_digest_counts_set_bits() {
        assert_eq!(login_digest(""), format!("{DIGEST_HEAD}{DIGEST_TAIL}"));
        assert_eq!(login_digest("a\u{0}\u{7f}"), format!("{DIGEST_HEAD}307{DIGEST_TAIL}"));
        let p = parse_login(&login_payload("aubo", "123456").unwrap()).unwrap();
        assert_eq!((p.user.as_str(), p.version.as_str()), ("aubo", SDK_VERSION));
        assert_eq!(p.digest, login_digest("123456"));
        assert!(login_payload("a\nb", "x").is_err());
    }

    #[test]
    fn transports_parse_by_name() {
        for t in Transport::ALL {
            assert_eq!(t.name().parse::<Transport>().unwrap(), t);
        }
        assert!("tcp".parse::<Transport>().unwrap_err().contains("framed, lines or http"));
    }
}
