//! One connection's byte stream, without the socket: which transport it speaks, its requests
//! (each byte scanned once, none longer than [`MAX_REQUEST_BYTES`]), the framed login, and the
//! answers to send.

use serde_json::{Value, json};

use super::MAX_REQUEST_BYTES;
use super::dispatch::{NOT_LOGGED_IN, Reply, Shared, err, handle, parse_error};
use crate::wire::{self, FrameDecoder, HttpDecoder, JsonTextDecoder, Transport};

/// How the session reads its stream.
enum Decoder {
    /// Not known yet: waiting for the first byte that is not whitespace.
    Detect,
    Framed(FrameDecoder),
    Lines(JsonTextDecoder),
    Http(HttpDecoder),
}

/// What a piece of the stream produced.
#[derive(Default)]
pub(super) struct Output {
    /// Answers to send, in order, each in one write.
    pub(super) messages: Vec<Vec<u8>>,
    /// Close the connection after sending them.
    pub(super) close: bool,
}

/// One session: a connection's protocol state. Dropping it frees motion if it owned it.
pub(super) struct Session<'a> {
    shared: &'a Shared,
    id: u64,
    transports: Vec<Transport>,
    decoder: Decoder,
    logged_in: bool,
    /// Whitespace seen before the transport was known, bytes.
    leading: usize,
}

impl<'a> Session<'a> {
    /// A session speaking one of `transports` (the first byte tells them apart when there are
    /// several).
    pub(super) fn new(shared: &'a Shared, transports: &[Transport]) -> Self {
        let mut s = Session {
            shared,
            id: shared.new_session(),
            transports: transports.to_vec(),
            decoder: Decoder::Detect,
            logged_in: false,
            leading: 0,
        };
        if let [t] = transports {
            s.decoder = decoder(*t);
        }
        s
    }

    /// Takes the next bytes of the stream; returns the answers to the requests they complete.
    pub(super) fn feed(&mut self, bytes: &[u8]) -> Output {
        let mut out = Output::default();
        let mut bytes = bytes;
        if matches!(self.decoder, Decoder::Detect) {
            // Whitespace before the first request is dropped as it comes, up to the limit.
            let n = bytes.iter().position(|b| !b.is_ascii_whitespace()).unwrap_or(bytes.len());
            self.leading += n;
            bytes = &bytes[n..];
            if self.leading > MAX_REQUEST_BYTES {
                out.close = true;
                return out;
            }
            let Some(&first) = bytes.first() else { return out };
            let t = match first {
                b'S' => Transport::Framed,
                b'{' | b'[' => Transport::Lines,
                b'A'..=b'Z' => Transport::Http,
                _ => {
                    out.close = true; // none of the three: hang up
                    return out;
                }
            };
            if !self.transports.contains(&t) {
                out.close = true; // not served on this port
                return out;
            }
            self.decoder = decoder(t);
        }
        match &mut self.decoder {
            Decoder::Detect => {}
            Decoder::Framed(d) => d.push(bytes),
            Decoder::Lines(d) => d.push(bytes),
            Decoder::Http(d) => d.push(bytes),
        }
        while !out.close {
            let more = match self.decoder {
                Decoder::Detect => false,
                Decoder::Framed(_) => self.next_framed(&mut out),
                Decoder::Lines(_) => self.next_line(&mut out),
                Decoder::Http(_) => self.next_http(&mut out),
            };
            if !more {
                break;
            }
        }
        out
    }

    /// Answers the next frame; false when there is none yet.
    fn next_framed(&mut self, out: &mut Output) -> bool {
        let Decoder::Framed(d) = &mut self.decoder else { return false };
        let payload = match d.next_frame() {
            Ok(Some(p)) => p,
            Ok(None) => return false,
            Err(_) if !d.in_sync() => {
                // Not the framed format at all: hang up (a frame would not be understood).
                out.close = true;
                return false;
            }
            Err(e) => {
                // The stream cannot be resynchronised: say why (as a frame), then close.
                let a = json!({"jsonrpc": "2.0", "id": null, "error": {"code": -32600, "message": e.to_string()}});
                if let Ok(f) = wire::encode_frame(wire::sdk_json(&a).as_bytes()) {
                    out.messages.push(f);
                }
                out.close = true;
                return false;
            }
        };
        let answer = if let Some(req) = wire::parse_login(&payload) {
            self.logged_in = self.shared.login_ok(&req.user, &req.digest);
            wire::login_reply(self.logged_in)
        } else {
            let reply = match serde_json::from_slice::<Value>(&payload) {
                Err(e) => Reply::Answer(parse_error(&e.to_string())),
                Ok(v) if !self.logged_in && v.get("method") != Some(&json!("SystemInfo.getInterfaceVersionCode")) => {
                    err(
                        &v.get("id").cloned().unwrap_or(Value::Null),
                        NOT_LOGGED_IN,
                        "not logged in: send the __login__ message first",
                    )
                }
                Ok(v) => handle(&v, self.shared, self.id),
            };
            match reply {
                Reply::Answer(a) => wire::sdk_json(&a).into_bytes(),
                Reply::Drop => {
                    out.close = true;
                    return false;
                }
            }
        };
        match wire::encode_frame(&answer) {
            Ok(f) => out.messages.push(f),
            Err(_) => out.close = true,
        }
        !out.close
    }

    /// Answers the next line-delimited JSON text; false when there is none yet.
    fn next_line(&mut self, out: &mut Output) -> bool {
        let Decoder::Lines(d) = &mut self.decoder else { return false };
        let text = match d.next_text() {
            Ok(Some(t)) => t,
            Ok(None) => return false,
            Err(e) => {
                out.messages.push(line(&parse_error(&format!("{e}; closing the connection"))));
                out.close = true;
                return false;
            }
        };
        let v = match serde_json::from_slice::<Value>(&text) {
            Ok(v) => v,
            Err(e) => {
                out.messages.push(line(&parse_error(&format!("{e}; closing the connection"))));
                out.close = true;
                return false;
            }
        };
        match handle(&v, self.shared, self.id) {
            Reply::Answer(a) => out.messages.push(line(&a)),
            Reply::Drop => out.close = true,
        }
        !out.close
    }

    /// JSON-RPC over HTTP/1.1: `POST` (any path) with a `Content-Length` JSON body, answered
    /// `200 OK` with the JSON-RPC answer; keep-alive unless the request says
    /// `Connection: close`. Anything else is answered 400 (malformed: conflicting lengths, a
    /// head or body over the limits), 405 (not a POST) or 411 (no length) and closed. False
    /// when there is no whole request yet.
    fn next_http(&mut self, out: &mut Output) -> bool {
        let Decoder::Http(d) = &mut self.decoder else { return false };
        let refuse = |out: &mut Output, status: u16, reason: &str, message: &str| {
            let body = json!({"error": message}).to_string();
            out.messages.push(wire::http_response(status, reason, body.as_bytes(), true));
            out.close = true;
            false
        };
        let (head, body) = match d.next_message() {
            Ok(Some(m)) => m,
            Ok(None) => return false,
            Err(e) => return refuse(out, 400, "Bad Request", &e.to_string()),
        };
        if !head.start.starts_with("POST ") {
            return refuse(out, 405, "Method Not Allowed", "JSON-RPC requests are POSTed");
        }
        if head.header("content-length").is_none() {
            return refuse(out, 411, "Length Required", "send the JSON-RPC request with a Content-Length");
        }
        let close = head.header("connection").is_some_and(|v| v.eq_ignore_ascii_case("close"));
        let reply = match serde_json::from_slice::<Value>(&body) {
            Err(e) => Reply::Answer(parse_error(&e.to_string())),
            Ok(v) => handle(&v, self.shared, self.id),
        };
        let Reply::Answer(a) = reply else {
            out.close = true;
            return false;
        };
        out.messages.push(wire::http_response(200, "OK", wire::sdk_json(&a).as_bytes(), close));
        out.close = close;
        !close
    }
}

impl Drop for Session<'_> {
    fn drop(&mut self) {
        self.shared.release(self.id);
    }
}

fn decoder(t: Transport) -> Decoder {
    match t {
        Transport::Framed => Decoder::Framed(FrameDecoder::new(MAX_REQUEST_BYTES)),
        Transport::Lines => Decoder::Lines(JsonTextDecoder::new(MAX_REQUEST_BYTES)),
        Transport::Http => Decoder::Http(HttpDecoder::new(MAX_REQUEST_BYTES)),
    }
}

fn line(v: &Value) -> Vec<u8> {
    let mut b = serde_json::to_vec(v).unwrap_or_default();
    b.push(b'\n');
    b
}
