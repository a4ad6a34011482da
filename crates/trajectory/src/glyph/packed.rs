//! The packed hanzi-writer-data blob: every character's stroke outlines and medians in a compact
//! binary form, in chunks compressed independently so that one lookup inflates one chunk.
//!
//! Layout (little-endian; see docs/trajectory.md, "The embedded glyph data"):
//!
//! ```text
//! header   magic "MAOBIHZ1", u32 characters N, u32 characters per chunk K, u32 subset size S,
//!          u32 chunks C, u64 FNV-1a hash of everything after the header
//! index    N × u32 code points, ascending; (C + 1) × u32 chunk offsets into the chunk area;
//!          S × u32 code points of the frequency subset, in its order
//! chunks   each raw DEFLATE of: (k + 1) × u32 offsets into the op stream, (k + 1) × u32
//!          offsets into the number stream, the op stream, the number stream
//! ```
//!
//! A character's ops are: varint strokes, then per stroke varint elements and one byte per
//! element (0 move, 1 line, 2 quad, 3 cubic, 4 close), then per stroke varint median points.
//! Its numbers are the points of the outlines then of the medians, x and y each as the
//! zig-zag varint of the difference from the previous x (or y) of the character (starting at 0),
//! in the original frame of the data (y up); a number that is not an integer, or too far from
//! the previous one, is [`ESCAPE`] then its 8 bytes (`f64`), and leaves the previous unchanged.
//! Decoding gives back the very `f64`s the JSON parser gave.

use kurbo::{BezPath, PathEl, Point};

use super::{RawHanzi, limits};

/// The blob's first bytes (the last one is the format's version).
const MAGIC: &[u8; 8] = b"MAOBIHZ1";
/// Bytes of the header.
const HEADER_LEN: usize = 8 + 4 * 4 + 8;
/// The number code that says "a raw `f64` follows".
const ESCAPE: u64 = 0x3FFF;
/// Characters per chunk written by [`pack`].
pub(crate) const CHUNK_CHARS: usize = 64;
/// The most bytes one chunk may inflate to (a chunk of 64 characters is about 60 KB).
const MAX_CHUNK_BYTES: usize = 8 << 20;

/// FNV-1a, 64 bits.
fn fnv1a(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| (h ^ u64::from(b)).wrapping_mul(0x100_0000_01b3))
}

fn zigzag(v: i64) -> u64 {
    ((v << 1) ^ (v >> 63)) as u64
}

fn unzigzag(u: u64) -> i64 {
    ((u >> 1) as i64) ^ -((u & 1) as i64)
}

fn put_varint(out: &mut Vec<u8>, mut v: u64) {
    while v >= 0x80 {
        out.push((v as u8) | 0x80);
        v >>= 7;
    }
    out.push(v as u8);
}

fn put_u32(out: &mut Vec<u8>, v: usize) -> Result<(), String> {
    let v = u32::try_from(v).map_err(|_| format!("{v} does not fit the blob's 32-bit fields"))?;
    out.extend_from_slice(&v.to_le_bytes());
    Ok(())
}

/// A cursor over bytes that reports running out instead of panicking.
struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
    what: &'static str,
}

impl<'a> Reader<'a> {
    fn new(bytes: &'a [u8], what: &'static str) -> Self {
        Reader { bytes, at: 0, what }
    }

    fn take(&mut self, n: usize) -> Result<&'a [u8], String> {
        let end = self.at.checked_add(n).filter(|&e| e <= self.bytes.len());
        let end = end.ok_or_else(|| format!("{} ends early at byte {}", self.what, self.at))?;
        let s = &self.bytes[self.at..end];
        self.at = end;
        Ok(s)
    }

    fn byte(&mut self) -> Result<u8, String> {
        Ok(self.take(1)?[0])
    }

    fn u32(&mut self) -> Result<usize, String> {
        let b = self.take(4)?;
        Ok(u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as usize)
    }

    fn u64(&mut self) -> Result<u64, String> {
        let b = self.take(8)?;
        Ok(u64::from_le_bytes([b[0], b[1], b[2], b[3], b[4], b[5], b[6], b[7]]))
    }

    fn varint(&mut self) -> Result<u64, String> {
        let mut v = 0u64;
        for shift in (0..64).step_by(7) {
            let b = self.byte()?;
            v |= u64::from(b & 0x7f) << shift;
            if b < 0x80 {
                return Ok(v);
            }
        }
        Err(format!("{}: a varint longer than 64 bits at byte {}", self.what, self.at))
    }

    /// A count bounded by `max`.
    fn count(&mut self, max: usize, what: &str) -> Result<usize, String> {
        let n = self.varint()?;
        if n > max as u64 {
            return Err(format!("{}: {n} {what}; at most {max}", self.what));
        }
        Ok(n as usize)
    }
}

/// The running x and y of one character's number stream.
#[derive(Default)]
struct Coder {
    prev: [i64; 2],
}

impl Coder {
    fn put(&mut self, out: &mut Vec<u8>, p: [f64; 2]) {
        for (axis, v) in p.into_iter().enumerate() {
            let delta = v - self.prev[axis] as f64;
            // Integers in the coordinate window code as their difference; the rest (halves,
            // quarters, ninths in the real data) as raw bits.
            let code = (v.fract() == 0.0 && v.abs() <= 1e6 && !(v == 0.0 && v.is_sign_negative()))
                .then(|| zigzag(delta as i64))
                .filter(|&c| c < ESCAPE);
            match code {
                Some(c) => {
                    put_varint(out, c);
                    self.prev[axis] = v as i64;
                }
                None => {
                    put_varint(out, ESCAPE);
                    out.extend_from_slice(&v.to_le_bytes());
                }
            }
        }
    }

    fn get(&mut self, r: &mut Reader<'_>) -> Result<Point, String> {
        let mut p = [0.0; 2];
        for (axis, slot) in p.iter_mut().enumerate() {
            let c = r.varint()?;
            *slot = if c == ESCAPE {
                f64::from_le_bytes(r.u64()?.to_le_bytes())
            } else {
                if c > ESCAPE {
                    return Err(format!("{}: number code {c} beyond the escape", r.what));
                }
                let v = self.prev[axis] + unzigzag(c);
                self.prev[axis] = v;
                v as f64
            };
        }
        Ok(Point::new(p[0], p[1]))
    }
}

/// Appends one character's ops and numbers.
/// A path element's op code (0 move, 1 line, 2 quadratic, 3 cubic, 4 close) and its points.
fn op_and_points(el: &PathEl) -> (u8, Vec<Point>) {
    match *el {
        PathEl::MoveTo(a) => (0, vec![a]),
        PathEl::LineTo(a) => (1, vec![a]),
        PathEl::QuadTo(a, b) => (2, vec![a, b]),
        PathEl::CurveTo(a, b, c) => (3, vec![a, b, c]),
        PathEl::ClosePath => (4, vec![]),
    }
}

fn encode(raw: &RawHanzi, ops: &mut Vec<u8>, nums: &mut Vec<u8>) {
    let mut coder = Coder::default();
    put_varint(ops, raw.outlines.len() as u64);
    for path in &raw.outlines {
        put_varint(ops, path.elements().len() as u64);
        for el in path.elements() {
            let (op, points) = op_and_points(el);
            ops.push(op);
            for p in points {
                coder.put(nums, [p.x, p.y]);
            }
        }
    }
    for m in &raw.medians {
        put_varint(ops, m.len() as u64);
        for &p in m {
            coder.put(nums, p);
        }
    }
}

/// Decodes one character from its op and number streams, checking counts as it goes (the
/// values are checked by the caller, as for JSON).
fn decode(ops: &[u8], nums: &[u8]) -> Result<RawHanzi, String> {
    let mut o = Reader::new(ops, "embedded hanzi data (ops)");
    let mut n = Reader::new(nums, "embedded hanzi data (numbers)");
    let mut coder = Coder::default();
    let strokes = o.count(limits::MAX_STROKES, "strokes")?;
    let mut outlines = Vec::with_capacity(strokes);
    for _ in 0..strokes {
        let len = o.count(limits::MAX_PATH_ELEMENTS, "path elements")?;
        let mut els = Vec::with_capacity(len);
        for k in 0..len {
            let op = o.byte()?;
            let el = match op {
                0 => PathEl::MoveTo(coder.get(&mut n)?),
                1 => PathEl::LineTo(coder.get(&mut n)?),
                2 => PathEl::QuadTo(coder.get(&mut n)?, coder.get(&mut n)?),
                3 => PathEl::CurveTo(coder.get(&mut n)?, coder.get(&mut n)?, coder.get(&mut n)?),
                4 => PathEl::ClosePath,
                _ => return Err(format!("{}: unknown path op {op}", o.what)),
            };
            if k == 0 && !matches!(el, PathEl::MoveTo(_)) {
                return Err(format!("{}: a stroke outline that does not start with a move", o.what));
            }
            els.push(el);
        }
        outlines.push(BezPath::from_vec(els));
    }
    let mut medians = Vec::with_capacity(strokes);
    for _ in 0..strokes {
        let len = o.count(limits::MAX_MEDIAN_POINTS, "median points")?;
        let m = (0..len).map(|_| coder.get(&mut n).map(|p| [p.x, p.y])).collect::<Result<Vec<_>, _>>()?;
        medians.push(m);
    }
    if o.at != ops.len() || n.at != nums.len() {
        return Err("embedded hanzi data: bytes left over after a character".into());
    }
    Ok(RawHanzi { outlines, medians })
}

impl RawHanzi {
    /// Every element's kind and every number's bits (so that -0.0 and 0.0 differ): equal
    /// vectors mean bit-identical data.
    pub(crate) fn bits(&self) -> Vec<u64> {
        let mut v: Vec<u64> = vec![self.outlines.len() as u64];
        for p in &self.outlines {
            v.push(p.elements().len() as u64);
        }
        for el in self.outlines.iter().flat_map(|p| p.elements()) {
            let (kind, pts) = op_and_points(el);
            v.push(u64::from(kind));
            v.extend(pts.iter().flat_map(|q| [q.x.to_bits(), q.y.to_bits()]));
        }
        for m in &self.medians {
            v.push(m.len() as u64);
            v.extend(m.iter().flatten().map(|x| x.to_bits()));
        }
        v
    }
}

/// Packs characters (any order; each at most once) and the subset's order into a blob, then
/// decodes every character of it and requires the very same data back.
pub(crate) fn pack(chars: &[(char, RawHanzi)], subset: &[char]) -> Result<Vec<u8>, String> {
    let mut order: Vec<usize> = (0..chars.len()).collect();
    order.sort_by_key(|&i| chars[i].0);
    if order.windows(2).any(|w| chars[w[0]].0 == chars[w[1]].0) {
        return Err("a character is given twice".into());
    }
    if let Some(c) = subset.iter().find(|c| !chars.iter().any(|(d, _)| d == *c)) {
        return Err(format!("subset character {c:?} has no data"));
    }
    let mut index = Vec::new();
    for &i in &order {
        put_u32(&mut index, chars[i].0 as usize)?;
    }
    let mut area = Vec::new();
    let mut offsets = vec![0];
    for group in order.chunks(CHUNK_CHARS) {
        let (mut ops, mut nums) = (Vec::new(), Vec::new());
        let (mut op_at, mut num_at) = (vec![0], vec![0]);
        for &i in group {
            encode(&chars[i].1, &mut ops, &mut nums);
            op_at.push(ops.len());
            num_at.push(nums.len());
        }
        let mut plain = Vec::new();
        for v in op_at.into_iter().chain(num_at) {
            put_u32(&mut plain, v)?;
        }
        plain.extend_from_slice(&ops);
        plain.extend_from_slice(&nums);
        area.extend_from_slice(&miniz_oxide::deflate::compress_to_vec(&plain, 10));
        offsets.push(area.len());
    }
    for &o in &offsets {
        put_u32(&mut index, o)?;
    }
    for &c in subset {
        put_u32(&mut index, c as usize)?;
    }
    index.extend_from_slice(&area);
    let mut blob = MAGIC.to_vec();
    for v in [chars.len(), CHUNK_CHARS, subset.len(), offsets.len() - 1] {
        put_u32(&mut blob, v)?;
    }
    blob.extend_from_slice(&fnv1a(&index).to_le_bytes());
    blob.extend_from_slice(&index);
    let mut k = 0;
    Blob::open(&blob)?.verify(|ch, raw| {
        let (want_ch, want) = &chars[order[k]];
        k += 1;
        if ch != *want_ch || raw.bits() != want.bits() {
            return Err(format!("{want_ch:?} does not decode to its data"));
        }
        Ok(())
    })?;
    Ok(blob)
}

/// A checked view of a blob's header and index (the chunks are inflated on demand).
pub(crate) struct Blob<'a> {
    /// Code points, ascending.
    codes: &'a [u8],
    /// Chunk offsets (C + 1 of them).
    offsets: &'a [u8],
    /// The subset's code points, in order.
    subset: &'a [u8],
    /// The chunk area.
    area: &'a [u8],
    /// Characters per chunk.
    per_chunk: usize,
    /// The hash the header states.
    hash: u64,
    /// Everything after the header.
    body: &'a [u8],
}

fn u32_at(s: &[u8], i: usize) -> usize {
    u32::from_le_bytes([s[4 * i], s[4 * i + 1], s[4 * i + 2], s[4 * i + 3]]) as usize
}

impl<'a> Blob<'a> {
    /// Reads the header and slices the index. Cheap: hashes nothing, inflates nothing.
    pub(crate) fn open(bytes: &'a [u8]) -> Result<Self, String> {
        let mut r = Reader::new(bytes, "embedded hanzi data");
        if r.take(MAGIC.len())? != MAGIC {
            return Err("embedded hanzi data: not a maobi hanzi blob (wrong magic)".into());
        }
        let (n, per_chunk, s, c) = (r.u32()?, r.u32()?, r.u32()?, r.u32()?);
        let hash = r.u64()?;
        let body = &bytes[HEADER_LEN..];
        if per_chunk == 0 || c != n.div_ceil(per_chunk) {
            return Err(format!("embedded hanzi data: {c} chunks for {n} characters at {per_chunk} a chunk"));
        }
        let codes = r.take(4 * n)?;
        let offsets = r.take(4 * (c + 1))?;
        let subset = r.take(4 * s)?;
        let area = &bytes[r.at..];
        let blob = Blob { codes, offsets, subset, area, per_chunk, hash, body };
        let last = u32_at(offsets, c);
        if last != area.len() || (0..c).any(|i| u32_at(offsets, i) > u32_at(offsets, i + 1)) {
            return Err("embedded hanzi data: chunk offsets out of order or beyond the data".into());
        }
        Ok(blob)
    }

    /// Number of characters.
    pub(crate) fn len(&self) -> usize {
        self.codes.len() / 4
    }

    /// The `i`-th code point (ascending order).
    fn code(&self, i: usize) -> u32 {
        u32_at(self.codes, i) as u32
    }

    /// The characters of the frequency subset, in order (code points that are not characters
    /// are left out: a check elsewhere refuses them).
    pub(crate) fn subset(&self) -> Vec<char> {
        (0..self.subset.len() / 4).filter_map(|i| char::from_u32(u32_at(self.subset, i) as u32)).collect()
    }

    /// Every character, ascending.
    pub(crate) fn chars(&self) -> Vec<char> {
        (0..self.len()).filter_map(|i| char::from_u32(self.code(i))).collect()
    }

    /// The position of `ch`, if present (binary search).
    fn find(&self, ch: char) -> Option<usize> {
        let (mut lo, mut hi) = (0, self.len());
        while lo < hi {
            let mid = (lo + hi) / 2;
            match self.code(mid).cmp(&(ch as u32)) {
                std::cmp::Ordering::Less => lo = mid + 1,
                std::cmp::Ordering::Greater => hi = mid,
                std::cmp::Ordering::Equal => return Some(mid),
            }
        }
        None
    }

    /// Inflates chunk `c` and returns it with its number of characters.
    fn chunk(&self, c: usize) -> Result<(Vec<u8>, usize), String> {
        let bytes = &self.area[u32_at(self.offsets, c)..u32_at(self.offsets, c + 1)];
        let plain = miniz_oxide::inflate::decompress_to_vec_with_limit(bytes, MAX_CHUNK_BYTES)
            .map_err(|e| format!("embedded hanzi data: chunk {c} does not inflate: {e}"))?;
        let k = self.per_chunk.min(self.len() - c * self.per_chunk);
        if plain.len() < 8 * (k + 1) {
            return Err(format!("embedded hanzi data: chunk {c} is too short"));
        }
        Ok((plain, k))
    }

    /// Decodes entry `j` of an inflated chunk of `k` entries.
    fn entry(plain: &[u8], k: usize, j: usize) -> Result<RawHanzi, String> {
        let table = 8 * (k + 1);
        let ops_len = u32_at(plain, k);
        let nums_len = u32_at(plain, 2 * k + 1);
        let (o0, o1, n0, n1) =
            (u32_at(plain, j), u32_at(plain, j + 1), u32_at(plain, k + 1 + j), u32_at(plain, k + 2 + j));
        if o0 > o1 || n0 > n1 || o1 > ops_len || n1 > nums_len || table + ops_len + nums_len != plain.len() {
            return Err("embedded hanzi data: a chunk's offsets do not match its streams".into());
        }
        let ops = &plain[table..table + ops_len];
        let nums = &plain[table + ops_len..];
        decode(&ops[o0..o1], &nums[n0..n1])
    }

    /// The raw data of `ch`, or `None` when the blob does not have it.
    pub(crate) fn get(&self, ch: char) -> Result<Option<RawHanzi>, String> {
        let Some(i) = self.find(ch) else { return Ok(None) };
        let c = i / self.per_chunk;
        let (plain, k) = self.chunk(c)?;
        Self::entry(&plain, k, i - c * self.per_chunk).map(Some)
    }

    /// Checks the hash, the order of the index, the subset, and decodes every character, handing
    /// each to `each`.
    pub(crate) fn verify(&self, mut each: impl FnMut(char, RawHanzi) -> Result<(), String>) -> Result<(), String> {
        if fnv1a(self.body) != self.hash {
            return Err("embedded hanzi data: the hash does not match the contents".into());
        }
        if (1..self.len()).any(|i| self.code(i - 1) >= self.code(i)) {
            return Err("embedded hanzi data: the index is not strictly ascending".into());
        }
        let chars = self.chars();
        if chars.len() != self.len() {
            return Err("embedded hanzi data: the index holds a code point that is not a character".into());
        }
        if self.subset().len() * 4 != self.subset.len() || self.subset().iter().any(|&c| self.find(c).is_none()) {
            return Err("embedded hanzi data: a subset character is not in the index".into());
        }
        for c in 0..self.offsets.len() / 4 - 1 {
            let (plain, k) = self.chunk(c)?;
            for j in 0..k {
                each(chars[c * self.per_chunk + j], Self::entry(&plain, k, j)?)?;
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn raw(seed: i64) -> RawHanzi {
        let mut p = BezPath::new();
        p.move_to((100.0 + seed as f64, 200.0));
        p.quad_to((150.5, -119.0), (1023.0, 0.25));
        p.curve_to((1.0 / 3.0, 5.0), (-0.0, 7.0), (8.0, 9.0));
        p.line_to((1e6 + 2.0, -4000.0));
        p.close_path();
        RawHanzi { outlines: vec![p], medians: vec![vec![[367.222_222_222_222_23, 1.0], [2.0, 3.0]]] }
    }

    #[test]
    fn round_trips_bit_for_bit_and_finds_every_character() {
        let chars: Vec<(char, RawHanzi)> =
            (0..150).map(|i| (char::from_u32(0x4E00 + 7 * i as u32).unwrap(), raw(i))).collect();
        let blob = pack(&chars, &['\u{4E07}', '\u{4E00}']).unwrap();
        let b = Blob::open(&blob).unwrap();
        assert_eq!(b.len(), 150);
        assert_eq!(b.subset(), vec!['\u{4E07}', '\u{4E00}']);
        for (c, r) in &chars {
            assert_eq!(b.get(*c).unwrap().unwrap().bits(), r.bits(), "{c}");
        }
        assert!(b.get('a').unwrap().is_none());
        // "The same" is bit for bit: the signed zero survives and is told apart.
        let zero = |z: f64| RawHanzi { outlines: vec![], medians: vec![vec![[z, 1.0]]] }.bits();
        assert_ne!(zero(0.0), zero(-0.0));
        let mut n = 0;
        b.verify(|_, _| {
            n += 1;
            Ok(())
        })
        .unwrap();
        assert_eq!(n, 150);
        // A flipped byte in a chunk fails the hash and, where it breaks the stream, decoding.
        let mut bad = blob.clone();
        let last = bad.len() - 3;
        bad[last] ^= 0x55;
        assert!(Blob::open(&bad).unwrap().verify(|_, _| Ok(())).is_err());
        // Truncations are errors, never panics.
        for cut in [0, 7, HEADER_LEN, HEADER_LEN + 10, blob.len() - 1] {
            if let Ok(b) = Blob::open(&blob[..cut]) {
                let _ = b.get('\u{4E00}');
            }
        }
        assert!(pack(&[(chars[0].0, raw(0)), (chars[0].0, raw(1))], &[]).is_err());
    }
}
