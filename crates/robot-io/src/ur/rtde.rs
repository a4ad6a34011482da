//! UR's Real-Time Data Exchange (RTDE) protocol on port 30004, the parts maobi uses, for the
//! client ([`RtdeClient`]) and the simulator alike.
//!
//! Every package is a big-endian `u16` size (the whole package, these three bytes included), a
//! command byte and a payload (UR's RTDE guide, docs.universal-robots.com, "Real-Time Data
//! Exchange (RTDE) Guide"; the same layout as UR's own Python client, `rtde/rtde.py`, vendored in
//! `third_party/rtde-python-client` for the tests):
//!
//! | command | request payload | answer payload |
//! |---|---|---|
//! | `V` request protocol version | `u16` version (2) | `u8` accepted |
//! | `v` get URControl version | none | `u32` major, minor, bugfix, build |
//! | `O` setup outputs (v2) | `f64` frequency, then the field names, comma-separated | `u8` recipe id, then the types, comma-separated (`NOT_FOUND` for an unknown name) |
//! | `I` setup inputs | the field names | `u8` recipe id, then the types |
//! | `S` start | none | `u8` accepted |
//! | `P` pause | none | `u8` accepted |
//! | `U` data package | — | `u8` recipe id, then the fields in recipe order, big-endian |
//! | `M` text message (v2) | — | `u8` length, message, `u8` length, source, `u8` level |

use std::io::{Read, Write};
use std::net::{SocketAddr, TcpStream, ToSocketAddrs};
use std::time::{Duration, Instant};

use crate::RobotError;

/// `V`: request the protocol version.
pub const REQUEST_PROTOCOL_VERSION: u8 = b'V';
/// `v`: get the URControl version.
pub const GET_URCONTROL_VERSION: u8 = b'v';
/// `M`: a text message.
pub const TEXT_MESSAGE: u8 = b'M';
/// `U`: a data package.
pub const DATA_PACKAGE: u8 = b'U';
/// `O`: set up the outputs (the recipe the controller sends).
pub const SETUP_OUTPUTS: u8 = b'O';
/// `I`: set up the inputs.
pub const SETUP_INPUTS: u8 = b'I';
/// `S`: start sending data packages.
pub const START: u8 = b'S';
/// `P`: pause.
pub const PAUSE: u8 = b'P';
/// The protocol version maobi asks for (2: output recipes with a frequency, text messages with a
/// source).
pub const PROTOCOL_VERSION: u16 = 2;
/// The largest package: its size is a `u16` that counts the header.
pub const MAX_PACKAGE_BYTES: usize = u16::MAX as usize;
/// The three header bytes.
pub const HEADER_BYTES: usize = 3;
/// The highest output frequency a UR e-Series controller serves, Hz.
pub const MAX_FREQUENCY_HZ: f64 = 500.0;

/// An RTDE field type, as the setup answers name it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FieldType {
    /// `BOOL`: one byte.
    Bool,
    /// `UINT8`.
    Uint8,
    /// `UINT32`.
    Uint32,
    /// `UINT64`.
    Uint64,
    /// `INT32`.
    Int32,
    /// `DOUBLE`.
    Double,
    /// `VECTOR3D`: three doubles.
    Vector3d,
    /// `VECTOR6D`: six doubles.
    Vector6d,
    /// `VECTOR6INT32`.
    Vector6Int32,
    /// `VECTOR6UINT32`.
    Vector6Uint32,
}

impl FieldType {
    /// The type's name on the wire (`VECTOR6D`).
    pub fn name(self) -> &'static str {
        match self {
            FieldType::Bool => "BOOL",
            FieldType::Uint8 => "UINT8",
            FieldType::Uint32 => "UINT32",
            FieldType::Uint64 => "UINT64",
            FieldType::Int32 => "INT32",
            FieldType::Double => "DOUBLE",
            FieldType::Vector3d => "VECTOR3D",
            FieldType::Vector6d => "VECTOR6D",
            FieldType::Vector6Int32 => "VECTOR6INT32",
            FieldType::Vector6Uint32 => "VECTOR6UINT32",
        }
    }

    /// The type named `name`, if it is one.
    pub fn parse(name: &str) -> Option<Self> {
        [
            FieldType::Bool,
            FieldType::Uint8,
            FieldType::Uint32,
            FieldType::Uint64,
            FieldType::Int32,
            FieldType::Double,
            FieldType::Vector3d,
            FieldType::Vector6d,
            FieldType::Vector6Int32,
            FieldType::Vector6Uint32,
        ]
        .into_iter()
        .find(|t| t.name() == name)
    }

    /// Bytes on the wire.
    pub fn size(self) -> usize {
        match self {
            FieldType::Bool | FieldType::Uint8 => 1,
            FieldType::Uint32 | FieldType::Int32 => 4,
            FieldType::Uint64 | FieldType::Double => 8,
            FieldType::Vector3d => 24,
            FieldType::Vector6d => 48,
            FieldType::Vector6Int32 | FieldType::Vector6Uint32 => 24,
        }
    }
}

/// The output fields maobi's client asks for and the simulator serves, with their types as UR
/// lists them (the RTDE guide; UR's client library, `src/rtde/data_package.cpp`).
pub const OUTPUT_FIELDS: [(&str, FieldType); 15] = [
    ("timestamp", FieldType::Double),
    ("actual_q", FieldType::Vector6d),
    ("actual_TCP_pose", FieldType::Vector6d),
    ("target_TCP_pose", FieldType::Vector6d),
    ("tcp_offset", FieldType::Vector6d),
    ("robot_mode", FieldType::Int32),
    ("safety_mode", FieldType::Int32),
    ("safety_status", FieldType::Int32),
    ("runtime_state", FieldType::Uint32),
    ("robot_status_bits", FieldType::Uint32),
    ("safety_status_bits", FieldType::Uint32),
    ("speed_scaling", FieldType::Double),
    ("target_speed_fraction", FieldType::Double),
    ("payload", FieldType::Double),
    ("output_int_register_24", FieldType::Int32),
];

/// The type of output field `name`, among [`OUTPUT_FIELDS`] and the output registers
/// (`output_int_register_0`..`47`: `INT32`, `output_double_register_0`..`47`: `DOUBLE`,
/// `output_bit_register_64`..`127`: `BOOL`).
pub fn output_type(name: &str) -> Option<FieldType> {
    if let Some((_, t)) = OUTPUT_FIELDS.iter().find(|(n, _)| *n == name) {
        return Some(*t);
    }
    let reg = |prefix: &str, range: std::ops::RangeInclusive<usize>| {
        name.strip_prefix(prefix)
            .filter(|d| !d.is_empty() && d.bytes().all(|b| b.is_ascii_digit()) && (d.len() == 1 || !d.starts_with('0')))
            .and_then(|d| d.parse::<usize>().ok())
            .is_some_and(|i| range.contains(&i))
    };
    if reg("output_int_register_", 0..=47) {
        Some(FieldType::Int32)
    } else if reg("output_double_register_", 0..=47) {
        Some(FieldType::Double)
    } else if reg("output_bit_register_", 64..=127) {
        Some(FieldType::Bool)
    } else {
        None
    }
}

/// A field's value.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Value {
    /// `BOOL`.
    Bool(bool),
    /// `UINT8`.
    Uint8(u8),
    /// `UINT32`.
    Uint32(u32),
    /// `UINT64`.
    Uint64(u64),
    /// `INT32`.
    Int32(i32),
    /// `DOUBLE`.
    Double(f64),
    /// `VECTOR3D`.
    Vector3d([f64; 3]),
    /// `VECTOR6D`.
    Vector6d([f64; 6]),
    /// `VECTOR6INT32`.
    Vector6Int32([i32; 6]),
    /// `VECTOR6UINT32`.
    Vector6Uint32([u32; 6]),
}

impl Value {
    /// Appends the value's bytes (big-endian).
    pub fn write(&self, out: &mut Vec<u8>) {
        match self {
            Value::Bool(b) => out.push(u8::from(*b)),
            Value::Uint8(v) => out.push(*v),
            Value::Uint32(v) => out.extend_from_slice(&v.to_be_bytes()),
            Value::Uint64(v) => out.extend_from_slice(&v.to_be_bytes()),
            Value::Int32(v) => out.extend_from_slice(&v.to_be_bytes()),
            Value::Double(v) => out.extend_from_slice(&v.to_be_bytes()),
            Value::Vector3d(v) => v.iter().for_each(|x| out.extend_from_slice(&x.to_be_bytes())),
            Value::Vector6d(v) => v.iter().for_each(|x| out.extend_from_slice(&x.to_be_bytes())),
            Value::Vector6Int32(v) => v.iter().for_each(|x| out.extend_from_slice(&x.to_be_bytes())),
            Value::Vector6Uint32(v) => v.iter().for_each(|x| out.extend_from_slice(&x.to_be_bytes())),
        }
    }

    /// Reads a value of type `t` from the start of `b` (at least `t.size()` bytes).
    fn read(t: FieldType, b: &[u8]) -> Value {
        let u32at = |i: usize| u32::from_be_bytes(b[i..i + 4].try_into().expect("4 bytes"));
        let f64at = |i: usize| f64::from_be_bytes(b[i..i + 8].try_into().expect("8 bytes"));
        match t {
            FieldType::Bool => Value::Bool(b[0] != 0),
            FieldType::Uint8 => Value::Uint8(b[0]),
            FieldType::Uint32 => Value::Uint32(u32at(0)),
            FieldType::Uint64 => Value::Uint64(u64::from_be_bytes(b[..8].try_into().expect("8 bytes"))),
            FieldType::Int32 => Value::Int32(u32at(0) as i32),
            FieldType::Double => Value::Double(f64at(0)),
            FieldType::Vector3d => Value::Vector3d(std::array::from_fn(|i| f64at(8 * i))),
            FieldType::Vector6d => Value::Vector6d(std::array::from_fn(|i| f64at(8 * i))),
            FieldType::Vector6Int32 => Value::Vector6Int32(std::array::from_fn(|i| u32at(4 * i) as i32)),
            FieldType::Vector6Uint32 => Value::Vector6Uint32(std::array::from_fn(|i| u32at(4 * i))),
        }
    }
}

/// One package with its header, ready to be written in one piece.
///
/// # Errors
/// [`RobotError::Framing`] when the payload does not fit a package ([`MAX_PACKAGE_BYTES`]).
pub fn encode(command: u8, payload: &[u8]) -> Result<Vec<u8>, RobotError> {
    let size = payload.len() + HEADER_BYTES;
    let size16 = u16::try_from(size).map_err(|_| {
        RobotError::Framing(format!("an RTDE package of {size} bytes exceeds the limit of {MAX_PACKAGE_BYTES}"))
    })?;
    let mut out = Vec::with_capacity(size);
    out.extend_from_slice(&size16.to_be_bytes());
    out.push(command);
    out.extend_from_slice(payload);
    Ok(out)
}

/// Splits a byte stream into packages, however it arrives; never holds more than one package
/// and one read.
#[derive(Debug, Default)]
pub struct PackageDecoder {
    buf: Vec<u8>,
}

impl PackageDecoder {
    /// Appends received bytes.
    pub fn push(&mut self, bytes: &[u8]) {
        self.buf.extend_from_slice(bytes);
    }

    /// Bytes held that do not yet make a package.
    pub fn pending(&self) -> usize {
        self.buf.len()
    }

    /// The next complete package, `(command, payload)`.
    ///
    /// # Errors
    /// [`RobotError::Framing`] for a size below the header's three bytes (the stream cannot be
    /// read further).
    pub fn next_package(&mut self) -> Result<Option<(u8, Vec<u8>)>, RobotError> {
        if self.buf.len() < HEADER_BYTES {
            return Ok(None);
        }
        let size = usize::from(u16::from_be_bytes([self.buf[0], self.buf[1]]));
        if size < HEADER_BYTES {
            return Err(RobotError::Framing(format!(
                "an RTDE package whose size field is {size} (at least the 3 header bytes)"
            )));
        }
        if self.buf.len() < size {
            return Ok(None);
        }
        let command = self.buf[2];
        let payload = self.buf[HEADER_BYTES..size].to_vec();
        self.buf.drain(..size);
        Ok(Some((command, payload)))
    }
}

/// The field values of a data package's payload for a recipe of `types`: the recipe id and the
/// values in order.
///
/// # Errors
/// [`RobotError::Protocol`] for a payload that is not the id and exactly those fields.
pub fn decode_data(types: &[FieldType], payload: &[u8]) -> Result<(u8, Vec<Value>), RobotError> {
    let want = 1 + types.iter().map(|t| t.size()).sum::<usize>();
    if payload.len() != want {
        return Err(RobotError::Protocol(format!(
            "RTDE data package of {} bytes where the recipe needs {want}",
            payload.len()
        )));
    }
    let mut at = 1;
    let mut values = Vec::with_capacity(types.len());
    for t in types {
        values.push(Value::read(*t, &payload[at..]));
        at += t.size();
    }
    Ok((payload[0], values))
}

/// The types of a setup answer's payload after the recipe id (`VECTOR6D,INT32,…`).
///
/// # Errors
/// [`RobotError::Protocol`] naming the field a type stands for when it is `NOT_FOUND`,
/// `IN_USE` or not a type.
pub fn parse_types(names: &[&str], text: &[u8]) -> Result<Vec<FieldType>, RobotError> {
    let text = std::str::from_utf8(text)
        .map_err(|_| RobotError::Protocol("RTDE setup answer: the types are not UTF-8".into()))?;
    let got: Vec<&str> = text.split(',').collect();
    if got.len() != names.len() {
        return Err(RobotError::Protocol(format!(
            "RTDE setup answer: {} types for {} fields ({text:?})",
            got.len(),
            names.len()
        )));
    }
    names
        .iter()
        .zip(got)
        .map(|(n, t)| {
            FieldType::parse(t).ok_or_else(|| {
                RobotError::Protocol(format!("the controller cannot send RTDE field `{n}`: it answered {t:?}"))
            })
        })
        .collect()
}

/// The URControl version, as `v` answers it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub struct ControlVersion {
    /// Major (5 for e-Series).
    pub major: u32,
    /// Minor.
    pub minor: u32,
    /// Bugfix.
    pub bugfix: u32,
    /// Build.
    pub build: u32,
}

impl std::fmt::Display for ControlVersion {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}.{}.{}.{}", self.major, self.minor, self.bugfix, self.build)
    }
}

/// Text messages kept from one connection (the rest are counted, not kept).
const MAX_MESSAGES: usize = 16;

/// An RTDE client: version 2 negotiated, one output recipe, then data packages.
pub struct RtdeClient {
    stream: TcpStream,
    decoder: PackageDecoder,
    timeout: Duration,
    addr: String,
    recipe: Option<(u8, Vec<FieldType>)>,
    /// Text messages the controller sent (`source: message`), the first ones.
    pub messages: Vec<String>,
}

impl RtdeClient {
    /// Connects to `addr` (`host:port`) and negotiates protocol version 2; `timeout` bounds the
    /// connection and every later answer.
    ///
    /// # Errors
    /// [`RobotError::Io`] when the connection fails; [`RobotError::Protocol`] when the controller
    /// refuses version 2 or answers out of the protocol; [`RobotError::Timeout`].
    pub fn connect(addr: &str, timeout: Duration) -> Result<Self, RobotError> {
        let stream = connect_stream(addr, timeout)?;
        let mut c = RtdeClient {
            stream,
            decoder: PackageDecoder::default(),
            timeout,
            addr: addr.to_string(),
            recipe: None,
            messages: Vec::new(),
        };
        let accepted = c.request(REQUEST_PROTOCOL_VERSION, &PROTOCOL_VERSION.to_be_bytes())?;
        if accepted != [1] {
            return Err(RobotError::Protocol(format!(
                "RTDE at {addr}: the controller refused protocol version {PROTOCOL_VERSION} (answered {accepted:?})"
            )));
        }
        Ok(c)
    }

    /// `v`: the controller's version.
    ///
    /// # Errors
    /// As [`RtdeClient::connect`].
    pub fn controller_version(&mut self) -> Result<ControlVersion, RobotError> {
        let p = self.request(GET_URCONTROL_VERSION, &[])?;
        if p.len() != 16 {
            return Err(RobotError::Protocol(format!("RTDE `v` answer of {} bytes (16 expected)", p.len())));
        }
        let u = |i: usize| u32::from_be_bytes(p[4 * i..4 * i + 4].try_into().expect("4 bytes"));
        Ok(ControlVersion { major: u(0), minor: u(1), bugfix: u(2), build: u(3) })
    }

    /// `O`: the output recipe `names` at `frequency_hz`; returns the types.
    ///
    /// # Errors
    /// [`RobotError::Protocol`] naming a field the controller cannot send; as
    /// [`RtdeClient::connect`].
    pub fn setup_outputs(&mut self, frequency_hz: f64, names: &[&str]) -> Result<Vec<FieldType>, RobotError> {
        let mut payload = frequency_hz.to_be_bytes().to_vec();
        payload.extend_from_slice(names.join(",").as_bytes());
        let p = self.request(SETUP_OUTPUTS, &payload)?;
        let (&id, types) = p.split_first().ok_or_else(|| RobotError::Protocol("RTDE `O` answer is empty".into()))?;
        let types = parse_types(names, types)?;
        if id == 0 {
            return Err(RobotError::Protocol("RTDE `O` answer: recipe id 0 (the setup was refused)".into()));
        }
        self.recipe = Some((id, types.clone()));
        Ok(types)
    }

    /// `S`: starts the data packages.
    ///
    /// # Errors
    /// [`RobotError::Protocol`] when refused; as [`RtdeClient::connect`].
    pub fn start(&mut self) -> Result<(), RobotError> {
        match self.request(START, &[])?.as_slice() {
            [1] => Ok(()),
            p => Err(RobotError::Protocol(format!("RTDE `S` (start) refused: {p:?}"))),
        }
    }

    /// The next data package's values (the recipe's order), waiting at most the timeout;
    /// text messages met on the way are kept in [`RtdeClient::messages`].
    ///
    /// # Errors
    /// [`RobotError::Timeout`] when none arrives in time; [`RobotError::Protocol`] for a
    /// package of another recipe or size; as [`RtdeClient::connect`].
    pub fn next_data(&mut self) -> Result<Vec<Value>, RobotError> {
        let Some((id, types)) = self.recipe.clone() else {
            return Err(RobotError::Protocol("RTDE: no output recipe set up".into()));
        };
        let p = self.wait_for(DATA_PACKAGE)?;
        let (got, values) = decode_data(&types, &p)?;
        if got != id {
            return Err(RobotError::Protocol(format!("RTDE data package of recipe {got}, expected {id}")));
        }
        Ok(values)
    }

    /// Sends `command` with `payload` and waits for the answer of the same command.
    fn request(&mut self, command: u8, payload: &[u8]) -> Result<Vec<u8>, RobotError> {
        let pkg = encode(command, payload)?;
        let what = format!("RTDE `{}` at {}", char::from(command), self.addr);
        self.stream.write_all(&pkg).map_err(|e| io_error(&what, e))?;
        self.wait_for(command)
    }

    /// The next package with `command`, skipping data packages and keeping text messages.
    fn wait_for(&mut self, command: u8) -> Result<Vec<u8>, RobotError> {
        let what = format!("RTDE `{}` at {}", char::from(command), self.addr);
        let deadline = Instant::now() + self.timeout;
        loop {
            while let Some((c, p)) = self.decoder.next_package()? {
                if c == command {
                    return Ok(p);
                }
                match c {
                    TEXT_MESSAGE => self.keep_message(&p),
                    DATA_PACKAGE => {}
                    _ => {
                        return Err(RobotError::Protocol(format!(
                            "{what}: an unexpected package `{}` ({} bytes)",
                            char::from(c),
                            p.len()
                        )));
                    }
                }
            }
            let now = Instant::now();
            if now >= deadline {
                return Err(RobotError::Timeout(what));
            }
            self.stream.set_read_timeout(Some(deadline - now)).map_err(|e| io_error(&what, e))?;
            let mut chunk = [0u8; 8192];
            match self.stream.read(&mut chunk) {
                Ok(0) => {
                    let e =
                        std::io::Error::new(std::io::ErrorKind::UnexpectedEof, "connection closed by the controller");
                    return Err(io_error(&what, e));
                }
                Ok(n) => self.decoder.push(&chunk[..n]),
                Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
                Err(e) => return Err(io_error(&what, e)),
            }
        }
    }

    fn keep_message(&mut self, p: &[u8]) {
        if self.messages.len() >= MAX_MESSAGES {
            return;
        }
        // v2: length, message, length, source, level.
        let text = (|| {
            let (&ml, rest) = p.split_first()?;
            let msg = rest.get(..usize::from(ml))?;
            let (&sl, rest) = rest.get(usize::from(ml)..)?.split_first()?;
            let src = rest.get(..usize::from(sl))?;
            Some(format!("{}: {}", String::from_utf8_lossy(src), String::from_utf8_lossy(msg)))
        })();
        self.messages.push(crate::export::comment_text(
            &text.unwrap_or_else(|| String::from_utf8_lossy(p).into_owned()),
            crate::export::ExportTarget::UrScript,
        ));
    }
}

/// A TCP connection to the first address of `addr` that answers within `timeout`, with
/// `timeout` for reads and writes.
pub(crate) fn connect_stream(addr: &str, timeout: Duration) -> Result<TcpStream, RobotError> {
    let addrs: Vec<SocketAddr> = addr.to_socket_addrs().map_err(|e| crate::aubo::io_at(addr, e))?.collect();
    let mut last = None;
    for a in addrs {
        match TcpStream::connect_timeout(&a, timeout) {
            Ok(s) => {
                s.set_read_timeout(Some(timeout)).map_err(|e| crate::aubo::io_at(addr, e))?;
                s.set_write_timeout(Some(timeout)).map_err(|e| crate::aubo::io_at(addr, e))?;
                let _ = s.set_nodelay(true);
                return Ok(s);
            }
            Err(e) => last = Some(e),
        }
    }
    let e = last.unwrap_or_else(|| std::io::Error::new(std::io::ErrorKind::AddrNotAvailable, "no address"));
    Err(crate::aubo::io_at(addr, e))
}

/// A timeout as [`RobotError::Timeout`], anything else as [`RobotError::Io`].
pub(crate) fn io_error(what: &str, e: std::io::Error) -> RobotError {
    match e.kind() {
        std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut => RobotError::Timeout(what.to_string()),
        _ => crate::aubo::io_at(what, e),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn packages_frame_and_values_round_trip() {
        let types = [FieldType::Double, FieldType::Vector6d, FieldType::Uint32, FieldType::Int32, FieldType::Bool];
        let values = [
            Value::Double(1.5),
            Value::Vector6d([0.1, -0.2, 0.3, 3.1, 0.0, -1.0]),
            Value::Uint32(2),
            Value::Int32(-7),
            Value::Bool(true),
        ];
        let mut payload = vec![3u8];
        values.iter().for_each(|v| v.write(&mut payload));
        let pkg = encode(DATA_PACKAGE, &payload).unwrap();
        assert_eq!(usize::from(u16::from_be_bytes([pkg[0], pkg[1]])), pkg.len());
        // Any split of the stream gives the package back.
        for cut in 0..pkg.len() {
            let mut d = PackageDecoder::default();
            d.push(&pkg[..cut]);
            assert!(d.next_package().unwrap().is_none());
            d.push(&pkg[cut..]);
            let (c, p) = d.next_package().unwrap().unwrap();
            assert_eq!((c, decode_data(&types, &p).unwrap()), (DATA_PACKAGE, (3, values.to_vec())));
        }
        // A short size field cannot be read past; a wrong payload size is named.
        let mut d = PackageDecoder::default();
        d.push(&[0, 2, b'U']);
        assert!(matches!(d.next_package(), Err(RobotError::Framing(_))));
        assert!(decode_data(&types, &payload[..payload.len() - 1]).is_err());
        assert!(encode(DATA_PACKAGE, &vec![0; MAX_PACKAGE_BYTES]).is_err());
    }

    #[test]
    fn output_types_cover_the_fields_and_registers() {
        assert_eq!(output_type("actual_TCP_pose"), Some(FieldType::Vector6d));
        assert_eq!(output_type("runtime_state"), Some(FieldType::Uint32));
        assert_eq!(output_type("output_int_register_47"), Some(FieldType::Int32));
        assert_eq!(output_type("output_int_register_48"), None);
        assert_eq!(output_type("output_int_register_07"), None);
        assert_eq!(output_type("output_bit_register_63"), None);
        assert_eq!(output_type("actual_tcp_pose"), None);
        let e = parse_types(&["a", "b"], b"DOUBLE,NOT_FOUND").unwrap_err().to_string();
        assert!(e.contains("`b`") && e.contains("NOT_FOUND"), "{e}");
    }
}
