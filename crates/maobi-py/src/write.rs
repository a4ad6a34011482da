//! Characters: `maobi.write`, `maobi.glyph`, `maobi.Track`, `maobi.Written`, and images on disk.

use std::path::{Path, PathBuf};

use brush_model::{Stroke, TrackPoint};
use pipeline::{GlyphInput, TextOptions, WriteOptions, prepare_loaded, write_text};
use pyo3::prelude::*;
use pyo3::types::PyList;
use robot_io::TrackFile;

use crate::arrays::{json_to_py, path_arg, rows, to_numpy};
use crate::brush::{Brush, brush_arg};
use crate::errors::value_err;
use crate::render::{box_arg, image_out, size_arg};
use crate::{MaobiError, guarded, lib_err};

/// The most pixels of one `write` call's images of one kind (2^28: 1,024 characters at 512 px;
/// three kinds of f32 images, about 3 GiB).
const MAX_WRITE_PIXELS: u64 = 1 << 28;

/// The most strokes of a `Track` made from Python (a sheet of 100 characters has about 1,500).
const MAX_STROKES: usize = 100_000;

/// Writes `bytes` to `path` through a temporary file beside it, renamed into place
/// (`safe_output::write_atomic`: the folder is created, a symlink is written through, a folder
/// or a special file is refused). Errors say `writing PATH: ` and why.
pub(crate) fn write_atomic(path: &Path, bytes: &[u8]) -> PyResult<()> {
    let context = format!("writing {}", path.display());
    safe_output::write_atomic(path, bytes).map_err(|e| match e {
        // The operating system's error after the path already said.
        safe_output::Error::Io { source, .. } => lib_err(&context, source),
        e => lib_err(&context, e),
    })
}

/// A brush track: strokes of points `x_mm, y_mm, h_mm, alpha_rad, beta_rad` on the paper (the
/// commanded motion; `h_mm <= 0` is off the paper), the brush it was made for and, when known,
/// the character and its box. Reads and writes `track.json` as `maobi write` does.
#[pyclass(module = "maobi", name = "Track", frozen)]
#[derive(Clone)]
pub(crate) struct Track {
    pub(crate) file: TrackFile,
}

#[pymethods]
impl Track {
    /// A track from strokes (a list of `(N, 5)` arrays: `x_mm, y_mm, h_mm, alpha_rad,
    /// beta_rad`), the brush (default pen1), and optionally the character and its box
    /// (`(x0_mm, y0_mm, side_mm)`).
    #[new]
    #[pyo3(signature = (strokes, *, brush = None, char = None, box_mm = None))]
    fn new(
        strokes: &Bound<'_, PyAny>,
        brush: Option<&Bound<'_, PyAny>>,
        char: Option<String>,
        box_mm: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Self> {
        let list: Vec<Bound<'_, PyAny>> = strokes
            .try_iter()
            .map_err(|_| value_err("strokes: expected a list of (N, 5) arrays"))?
            .take(MAX_STROKES + 1)
            .collect::<PyResult<_>>()?;
        if list.len() > MAX_STROKES {
            return Err(value_err(format!("strokes: more than {MAX_STROKES} strokes")));
        }
        let mut out = Vec::with_capacity(list.len());
        for (i, s) in list.iter().enumerate() {
            let pts = rows(s, &format!("strokes[{i}]"), 5, "x_mm, y_mm, h_mm, alpha_rad, beta_rad per point")?;
            out.push(Stroke {
                points: pts
                    .into_iter()
                    .map(|r| TrackPoint { x_mm: r[0], y_mm: r[1], h_mm: r[2], alpha_rad: r[3], beta_rad: r[4] })
                    .collect(),
            });
        }
        let char_box_mm = match box_mm.filter(|b| !b.is_none()) {
            Some(b) => {
                let c = box_arg(b, "box_mm")?;
                Some([c.x0_mm, c.y0_mm, c.size_mm])
            }
            None => None,
        };
        Ok(Self {
            file: TrackFile {
                char,
                char_box_mm,
                sheet_mm: None,
                brush: brush_arg(brush)?,
                strokes: out,
                stroke_chars: None,
            },
        })
    }

    /// Reads a `track.json` (a character's or a sheet's), validating its brush.
    #[staticmethod]
    fn load(path: &Bound<'_, PyAny>) -> PyResult<Self> {
        let p = crate::arrays::input_path(path, "path")?;
        TrackFile::load(&p).map(|file| Self { file }).map_err(|e| lib_err("path", e))
    }

    /// A track from the JSON text of a `track.json`.
    #[staticmethod]
    fn from_json(text: &str) -> PyResult<Self> {
        // The validation of `Track.load` (`stroke_chars` against the strokes and the sheet's
        // characters), not only the brush's.
        TrackFile::from_json(text, "text").map(|file| Self { file }).map_err(|e| match e {
            robot_io::RobotError::Json { source, .. } => {
                MaobiError::new_err(format!("text: not a track.json: {source}"))
            }
            e => lib_err("", e),
        })
    }

    /// The track as `track.json` text (what `maobi write` writes).
    fn to_json(&self) -> PyResult<String> {
        serde_json::to_string_pretty(&self.file).map_err(|e| lib_err("track", e))
    }

    /// Writes `track.json` to `path` (a temporary file, then renamed).
    fn save(&self, path: &Bound<'_, PyAny>) -> PyResult<()> {
        let p = path_arg(path, "path")?;
        write_atomic(&p, self.to_json()?.as_bytes())
    }

    /// The strokes: a list of `(N, 5)` float64 arrays (`x_mm, y_mm, h_mm, alpha_rad,
    /// beta_rad`), copies.
    #[getter]
    fn strokes<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyList>> {
        let arrays = self
            .file
            .strokes
            .iter()
            .map(|s| {
                let flat: Vec<f64> =
                    s.points.iter().flat_map(|p| [p.x_mm, p.y_mm, p.h_mm, p.alpha_rad, p.beta_rad]).collect();
                to_numpy(py, flat, &[s.points.len(), 5])
            })
            .collect::<PyResult<Vec<_>>>()?;
        PyList::new(py, arrays)
    }

    /// The brush the track was made for.
    #[getter]
    fn brush(&self) -> Brush {
        Brush { profile: self.file.brush.clone() }
    }

    /// The character, when recorded.
    #[getter]
    fn char(&self) -> Option<String> {
        self.file.char.clone()
    }

    /// The character's box on the paper, `(x0_mm, y0_mm, side_mm)`, when recorded.
    #[getter]
    fn box_mm(&self) -> Option<(f64, f64, f64)> {
        self.file.char_box_mm.map(|[x, y, s]| (x, y, s))
    }

    /// The number of points over all strokes.
    #[getter]
    fn point_count(&self) -> usize {
        self.file.strokes.iter().map(|s| s.points.len()).sum()
    }

    /// The number of strokes.
    fn __len__(&self) -> usize {
        self.file.strokes.len()
    }

    fn __repr__(&self) -> String {
        format!(
            "maobi.Track({}{} strokes, {} points, brush {:?})",
            self.file.char.as_ref().map_or(String::new(), |c| format!("{c:?}, ")),
            self.file.strokes.len(),
            self.point_count(),
            self.file.brush.name
        )
    }
}

/// One written character: its track, the reference glyph, the plan's render, what the executed
/// program writes, and the report (the fields of `maobi write`'s report.json).
#[pyclass(module = "maobi", name = "Written", frozen)]
pub(crate) struct Written {
    /// The brush track (what `track.json` holds).
    #[pyo3(get)]
    track: Py<Track>,
    /// The glyph rendered onto the character box, `(size_px, size_px)` float32, ink = 1
    /// (reference.png).
    #[pyo3(get)]
    reference: Py<PyAny>,
    /// The plan: the track rendered through the forward model (render.png).
    #[pyo3(get)]
    plan: Py<PyAny>,
    /// What the robot program writes, executed as `robot send` sends it (executed.png).
    #[pyo3(get)]
    executed: Py<PyAny>,
    /// The report: the fields of report.json (a dict).
    #[pyo3(get)]
    report: Py<PyAny>,
    /// The character.
    #[pyo3(get)]
    char: String,
}

#[pymethods]
impl Written {
    fn __repr__(&self, py: Python<'_>) -> String {
        let r = self.report.bind(py);
        let fig = |k: &str| -> String {
            r.get_item(k)
                .and_then(|v| v.get_item("csim"))
                .and_then(|v| v.extract::<f64>())
                .map_or("-".into(), |v| format!("{v:.4}"))
        };
        format!("maobi.Written({:?}, executed CSIM {}, plan CSIM {})", self.char, fig("executed"), fig("plan"))
    }
}

/// The glyph source of `font` (a path or a list of paths) and `hanzi_data`.
fn glyph_input(font: Option<&Bound<'_, PyAny>>, hanzi: Option<&Bound<'_, PyAny>>) -> PyResult<GlyphInput> {
    let hanzi = match hanzi.filter(|h| !h.is_none()) {
        Some(h) => {
            let p = path_arg(h, "hanzi_data")?;
            if !p.exists() {
                return Err(pyo3::exceptions::PyFileNotFoundError::new_err(format!(
                    "hanzi_data: {} does not exist (expected a hanzi-writer-data folder)",
                    p.display()
                )));
            }
            Some(p)
        }
        None => None,
    };
    let Some(font) = font.filter(|f| !f.is_none()) else {
        return Ok(GlyphInput::Hanzi(hanzi));
    };
    let paths: Vec<PathBuf> = if let Ok(p) = path_arg(font, "font") {
        vec![p]
    } else {
        font.try_iter()
            .map_err(|_| value_err("font: expected a path or a list of paths"))?
            .map(|f| path_arg(&f?, "font"))
            .collect::<PyResult<_>>()?
    };
    for p in &paths {
        if !p.exists() {
            return Err(pyo3::exceptions::PyFileNotFoundError::new_err(format!(
                "font: {} does not exist (expected a TTF, OTF, TTC, WOFF or WOFF2 file, or a folder of them)",
                p.display()
            )));
        }
        if !p.is_dir() {
            crate::arrays::input_file(p, "font")?;
        }
    }
    GlyphInput::fonts(&paths, None, hanzi).map_err(|e| lib_err("font", e))
}

/// A pipeline error as a Python exception: a character no source covers is a `ValueError`
/// naming the argument that could cover it.
fn pipeline_err(e: Box<pipeline::Error>) -> PyErr {
    match *e {
        pipeline::Error::Glyph(trajectory::GlyphError::Unknown { .. }) => value_err(format!(
            "text: {}: give font= (a CJK font file) or hanzi_data= (a hanzi-writer-data folder) that covers it",
            crate::errors::chain(&e)
        )),
        pipeline::Error::Profile(p) => crate::brush::profile_err("brush", p),
        e => lib_err("", e),
    }
}

/// The glyph of `c` and its centre lines.
fn prepare_char(input: &GlyphInput, c: char) -> PyResult<pipeline::Prepared> {
    match input.load(c) {
        Ok(l) => prepare_loaded(l, None).map_err(|e| pipeline_err(Box::new(e))),
        Err(e) => Err(pipeline_err(Box::new(e))),
    }
}

/// Writes characters as `maobi write TEXT` does (the same track, renders, executed program and
/// report, without the files): for each character of `text` (spaces left out) the glyph's
/// centre lines, the brush track in a character box sized for the brush, the plan rendered
/// through the forward model, the robot program checked and executed as `robot send` sends it,
/// and the scores. Returns one `Written` for one character, a list for several (laid out as
/// the CLI lays them out, one box size for all).
///
/// `brush`: a built-in name, a profile path or a `Brush`; `refine`: refine each track by
/// gradient descent against its glyph first (`iters` steps, default 20); `size_px`: side of
/// each image; `font`: glyphs from font files (a path or a list); `hanzi_data`: a
/// hanzi-writer-data folder; `alpha_rad`: constant brush tilt (radians, inside the brush's
/// range); `char_mm`: the character box side (mm; default sized for the brush);
/// `free_widths`: also score the plan with free footprint widths (`report["plan"]["free_widths"]`,
/// as `maobi write --free-widths`; a second track and render, so off by default).
#[pyfunction]
#[pyo3(signature = (text, brush = None, refine = false, size_px = 512, font = None, hanzi_data = None, alpha_rad = 0.0, *, char_mm = None, iters = None, free_widths = false))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn write<'py>(
    py: Python<'py>,
    text: &str,
    brush: Option<&Bound<'py, PyAny>>,
    refine: bool,
    size_px: i64,
    font: Option<&Bound<'py, PyAny>>,
    hanzi_data: Option<&Bound<'py, PyAny>>,
    alpha_rad: f64,
    char_mm: Option<f64>,
    iters: Option<usize>,
    free_widths: bool,
) -> PyResult<Bound<'py, PyAny>> {
    let chars: Vec<char> = text.chars().filter(|c| !c.is_whitespace()).collect();
    if chars.is_empty() {
        return Err(value_err("text is empty: expected at least one character"));
    }
    if chars.len() > 4096 {
        return Err(value_err(format!("text: {} characters (expected at most 4096 in one call)", chars.len())));
    }
    if !(64..=4096).contains(&size_px) {
        return Err(value_err(format!("size_px={size_px}: expected 64 to 4096 px (as `maobi write --size`)")));
    }
    let size = size_arg(size_px)?;
    // Three images a character (reference, plan, executed), all returned: their pixels are
    // bounded before any is made.
    let px = chars.len() as u64 * u64::from(size) * u64::from(size);
    if px > MAX_WRITE_PIXELS {
        return Err(value_err(format!(
            "text: {} characters at size_px={size_px}: {px} px an image set, expected at most {MAX_WRITE_PIXELS} \
             (fewer characters a call, or a smaller size_px)",
            chars.len()
        )));
    }
    let profile = brush_arg(brush)?;
    if !(alpha_rad.is_finite() && profile.ranges.alpha_rad.contains(alpha_rad)) {
        return Err(value_err(format!(
            "alpha_rad={alpha_rad}: outside the brush's calibrated tilt range {:.4}–{:.4} rad",
            profile.ranges.alpha_rad.min, profile.ranges.alpha_rad.max
        )));
    }
    if let Some(mm) = char_mm {
        if !(mm.is_finite() && (1.0..=1000.0).contains(&mm)) {
            return Err(value_err(format!("char_mm={mm}: expected 1 to 1000 mm (as `maobi write --char-mm`)")));
        }
    }
    if iters.is_some() && !refine {
        return Err(value_err("iters: only with refine=True"));
    }
    let refine = if refine {
        let mut o = track_refine::RefineOptions::default();
        if let Some(n) = iters {
            if !(1..=10_000).contains(&n) {
                return Err(value_err(format!("iters={n}: expected 1 to 10000 gradient steps")));
            }
            o.iterations = n;
        }
        Some(o)
    } else {
        None
    };
    let input = glyph_input(font, hanzi_data)?;
    let results = guarded(py, "write", move || {
        let prepared = chars.iter().map(|&c| prepare_char(&input, c)).collect::<PyResult<Vec<_>>>()?;
        let opts = WriteOptions { size, alpha_rad, refine, free_widths, ..WriteOptions::default() };
        let text = TextOptions { char_mm, ..TextOptions::default() };
        let w = write_text(prepared, &profile, &opts, &text, &|| {}).map_err(|e| pipeline_err(Box::new(e)))?;
        w.results
            .into_iter()
            .map(|r| {
                let report = serde_json::to_value(&r.report).map_err(|e| lib_err("report", e))?;
                Ok((r.track_file(&profile, None), r.reference, r.render, r.executed, report, r.report.char))
            })
            .collect::<PyResult<Vec<_>>>()
    })?;
    let mut out = Vec::with_capacity(results.len());
    for (file, reference, plan, executed, report, ch) in results {
        let w = Written {
            track: Py::new(py, Track { file })?,
            reference: image_out(py, reference)?.unbind(),
            plan: image_out(py, plan)?.unbind(),
            executed: match executed {
                Some(e) => image_out(py, e)?.unbind(),
                None => py.None(),
            },
            report: json_to_py(py, &report)?.unbind(),
            char: ch,
        };
        out.push(Py::new(py, w)?.into_any());
    }
    if out.len() == 1 { Ok(out.remove(0).into_bound(py)) } else { Ok(PyList::new(py, out)?.into_any()) }
}

/// The reference image of a character: its glyph rendered onto a `(size_px, size_px)` em box,
/// float32, ink = 1 (`maobi write`'s reference.png before encoding). `font` and `hanzi_data`
/// as in `write`.
#[pyfunction]
#[pyo3(signature = (char, size_px = 512, font = None, hanzi_data = None))]
pub(crate) fn glyph<'py>(
    py: Python<'py>,
    char: &str,
    size_px: i64,
    font: Option<&Bound<'py, PyAny>>,
    hanzi_data: Option<&Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyAny>> {
    let mut it = char.chars();
    let (Some(c), None) = (it.next(), it.next()) else {
        return Err(value_err(format!("char={char:?}: expected exactly one character")));
    };
    let size = size_arg(size_px)?;
    let input = glyph_input(font, hanzi_data)?;
    let img = guarded(py, "glyph", move || {
        let (g, _) = input.load(c).map_err(|e| pipeline_err(Box::new(e)))?;
        Ok(trajectory::render_glyph(&g, size))
    })?;
    image_out(py, img)
}

/// Reads an image (PNG or JPEG, dark ink on light paper) as `maobi compare` reads it: a
/// `(H, W)` float32 array, ink = 1.
#[pyfunction]
pub(crate) fn load_image<'py>(py: Python<'py>, path: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyAny>> {
    let p = crate::arrays::input_path(path, "path")?;
    let img = guarded(py, "load_image", move || bezier_raster::Coverage::load(&p).map_err(|e| lib_err("path", e)))?;
    image_out(py, img)
}

/// Writes a `(H, W)` image (ink = 1, values in [0, 1]) as an 8-bit grey PNG, dark ink on white,
/// as `maobi write` writes its images.
#[pyfunction]
pub(crate) fn save_image(py: Python<'_>, path: &Bound<'_, PyAny>, image: &Bound<'_, PyAny>) -> PyResult<()> {
    let p = path_arg(path, "path")?;
    let (data, h, w) = crate::arrays::image(image, "image")?;
    // What maobi reads back (`load_image`, `compare`): at most 16384 px a side, 64 Mpx in all.
    if h > 16384 || w > 16384 || h * w > 1 << 26 {
        return Err(value_err(format!("image: {w}×{h} px (expected at most 16384 px a side and 64 Mpx in all)")));
    }
    if let Some(v) = data.iter().find(|v| !(0.0..=1.0).contains(*v)) {
        return Err(value_err(format!("image: value {v} (expected coverage in [0, 1])")));
    }
    let png = guarded(py, "save_image", move || {
        let c = bezier_raster::Coverage::from_vec(w as u32, h as u32, data).map_err(|e| lib_err("image", e))?;
        c.encode_png().map_err(|e| lib_err("image", e))
    })?;
    write_atomic(&p, &png)
}
