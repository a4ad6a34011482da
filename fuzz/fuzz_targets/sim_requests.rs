//! The simulator's request parsing and dispatch, without sockets (`robot_io::sim::serve_bytes`):
//! the first byte picks the transports one session serves (bit 0 framed, bit 1 lines, bit 2
//! HTTP; none: all three, told apart by the first byte), the second the size of the pieces the
//! rest arrives in (1 to 256 bytes). It must answer or close, never panic, hang or allocate
//! beyond the request limit; the answer stays in proportion to the input.
#![no_main]

use libfuzzer_sys::fuzz_target;
use robot_io::sim::{SimOptions, serve_bytes};
use robot_io::wire::Transport;

fuzz_target!(|data: &[u8]| {
    let (pick, piece, stream) = match data {
        [p, s, rest @ ..] => (*p, usize::from(*s) + 1, rest),
        _ => return,
    };
    let transports: Vec<Transport> = [Transport::Framed, Transport::Lines, Transport::Http]
        .into_iter()
        .enumerate()
        .filter(|(i, _)| pick & (1 << i) != 0)
        .map(|(_, t)| t)
        .collect();
    let transports = if transports.is_empty() { Transport::ALL.to_vec() } else { transports };
    let pieces: Vec<&[u8]> = stream.chunks(piece).collect();
    let (out, _) = serve_bytes(SimOptions::default(), &transports, &pieces).expect("no trace file to create");
    assert!(out.len() <= 4096 + 512 * stream.len(), "{} answer bytes for {} request bytes", out.len(), stream.len());
});
