//! `cargo xtask fixtures [--check]`: every generated file under `fixtures/`, made
//! deterministically from code in this module.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use brush_model::{BrushProfile, Extrapolation, Press};

use numerics::SplitMix64 as SplitMix;

/// Inputs a generator may need.
pub struct Inputs {
    /// An unpacked hanzi-writer-data package (`npm pack hanzi-writer-data`), if given.
    pub hanzi_data: Option<PathBuf>,
    /// Generators that own several files (the photo set) write them when true, and compare
    /// them when false (`--check`).
    pub write_extra: bool,
}

/// One generated file.
struct Fixture {
    /// Path relative to the repository root.
    path: &'static str,
    /// What it holds, for the listing.
    about: &'static str,
    /// Whether it needs `--hanzi-data` (and so cannot be checked offline without it).
    needs_hanzi: bool,
    /// Whether it needs Python with numpy, scikit-image and statsmodels (golden values from
    /// independent tools); skipped, and said so, when they are not installed.
    needs_python: bool,
    /// Produces its bytes.
    generate: fn(&Inputs) -> Result<Vec<u8>>,
}

/// Characters the tests, gates and docs use; embedded even when not among the 1,000 most
/// frequent.
pub const EXTRA_CHARS: &str = "永字八法十口人丁山水火木中国书大小日月";

fn all() -> Vec<Fixture> {
    vec![
        Fixture {
            path: "fixtures/measurements/pen1-sample.csv",
            about: "synthetic pen1 measurements on the paper's grid (nominal model + 0.15 mm noise)",
            needs_hanzi: false,
            needs_python: false,
            generate: |_| sample_measurements(),
        },
        Fixture {
            path: "fixtures/photos/labels.csv",
            about: "labels of the synthetic stroke photos (file,h_mm,alpha_deg,beta_deg)",
            needs_hanzi: false,
            needs_python: false,
            generate: |_| Ok(photo_set()?.0),
        },
        Fixture {
            path: "fixtures/photos/photos.sha",
            about: "the synthetic stroke photos fixtures/photos/stroke_*.png (written alongside; this lists their sizes and FNV hashes)",
            needs_hanzi: false,
            needs_python: false,
            generate: photo_set_files,
        },
        Fixture {
            path: "crates/trajectory/data/hanzi-subset.jsonl",
            about: "hanzi-writer-data for the 1,000 most frequent characters plus the test set",
            needs_hanzi: true,
            needs_python: false,
            generate: hanzi_subset,
        },
        Fixture {
            path: "crates/trajectory/data/hanzi.bin",
            about: "every hanzi-writer-data character, packed and compressed in chunks (the embedded glyph data)",
            needs_hanzi: true,
            needs_python: false,
            generate: hanzi_blob,
        },
        Fixture {
            path: "fixtures/baselines/images/footprints-128.png",
            about: "pen1 h=15 α=5° β=3° with every stroke model side by side (bsm, circle, ellipse, line, qbc)",
            needs_hanzi: false,
            needs_python: false,
            generate: |_| footprint_sheet(),
        },
        Fixture {
            path: "fixtures/baselines/images/yong-medians-256.png",
            about: "永 written by the medians pipeline with nominal pen1, 256²",
            needs_hanzi: false,
            needs_python: false,
            generate: |_| character_render('永', trajectory::Method::Medians),
        },
        Fixture {
            path: "fixtures/baselines/images/yong-skeleton-256.png",
            about: "永 written by the skeleton pipeline with nominal pen1, 256²",
            needs_hanzi: false,
            needs_python: false,
            generate: |_| character_render('永', trajectory::Method::Skeleton),
        },
        Fixture {
            path: "crates/stroke-metrics/tests/golden/metrics.json",
            about: "CSIM/SSIM/IoU/MSE golden values from scikit-image and numpy",
            needs_hanzi: false,
            needs_python: true,
            generate: |_| python_golden("crates/stroke-metrics/tests/golden", "gen_metrics.py"),
        },
        Fixture {
            path: "crates/brush-model/tests/golden/regression.json",
            about: "regression golden table from statsmodels",
            needs_hanzi: false,
            needs_python: true,
            generate: |_| python_golden("crates/brush-model/tests/golden", "gen_regression.py"),
        },
        Fixture {
            path: "crates/trajectory/data/ARPHICPL.TXT",
            about: "the Arphic Public License shipped with the subset",
            needs_hanzi: true,
            needs_python: false,
            generate: |i| Ok(std::fs::read(hanzi_dir(i)?.join("ARPHICPL.TXT"))?),
        },
    ]
}

/// A file's name and bytes.
type NamedFile = (String, Vec<u8>);

/// The synthetic calibration set: 12 pressed strokes of nominal pen1 on a grid of h × α (β
/// alternating 0°/5°), photographed at 8 px/mm with blur, noise, an uneven background, specks,
/// JPEG artefacts and a slight rotation, saved as PNG with their scale. Returns the labels CSV
/// and the photos.
fn photo_set() -> Result<(Vec<u8>, Vec<NamedFile>)> {
    use stroke_fit::{Degradation, png_with_scale, synthetic_photo};
    let pen1 = BrushProfile::builtin("pen1")?;
    let px = 8.0;
    let mut labels = String::from("file,h_mm,alpha_deg,beta_deg\n");
    let mut files = Vec::new();
    let mut k = 0u64;
    for h in [11.0, 14.0, 17.0, 20.0] {
        for a in [0.0, 5.0, 10.0] {
            let b = if k % 2 == 0 { 0.0 } else { 5.0 };
            let press = Press::from_degrees(h, a, b);
            let fp = pen1.predict(&press, Extrapolation::Refuse)?;
            let turn = ((k as f64 * 0.37).sin() * 2.0).to_radians();
            let beta = press.beta_rad + turn;
            let side = ((fp.length_mm() + 10.0) * px).ceil() as u32;
            let c = fp.placed_bounds(brush_model::PointMm::default(), beta).centre();
            let half = side as f64 / px / 2.0;
            let anchor = brush_model::PointMm::new(half - c.x_mm, half - c.y_mm);
            let d = Degradation {
                blur_px: 1.0 + 0.1 * k as f64,
                noise: 0.03,
                gradient: 0.2 + 0.02 * k as f64,
                ..Degradation::default()
            };
            let g = synthetic_photo(&fp, anchor, beta, px, side, side, &d, 7000 + k);
            let name = format!("stroke_{:02}.png", k + 1);
            labels.push_str(&format!("{name},{h},{a},{b}\n"));
            files.push((name, png_with_scale(&g, side, side, px)));
            k += 1;
        }
    }
    Ok((labels.into_bytes(), files))
}

/// Writes (or, under `--check`, compares) the photos themselves, and returns their listing.
fn photo_set_files(inputs: &Inputs) -> Result<Vec<u8>> {
    let (_, files) = photo_set()?;
    let mut listing = String::new();
    for (name, bytes) in &files {
        let h = bytes.iter().fold(0xcbf2_9ce4_8422_2325u64, |h, b| (h ^ *b as u64).wrapping_mul(0x100_0000_01b3));
        listing.push_str(&format!("{name} {} {h:016x}\n", bytes.len()));
        let path = root().join("fixtures/photos").join(name);
        if inputs.write_extra {
            std::fs::create_dir_all(path.parent().expect("folder"))?;
            std::fs::write(&path, bytes)?;
        } else if std::fs::read(&path).ok().as_deref() != Some(bytes.as_slice()) {
            println!("DIFFERS  fixtures/photos/{name}");
            anyhow::bail!("fixtures/photos/{name} differs from what the generator produces now");
        }
    }
    Ok(listing.into_bytes())
}

fn footprint_sheet() -> Result<Vec<u8>> {
    use bezier_raster::{Compositor, ModelKind, Stamp, StrokeCanvas};
    let pen1 = BrushProfile::builtin("pen1")?;
    let press = Press::from_degrees(15.0, 5.0, 3.0);
    let fp = pen1.predict(&press, Extrapolation::Refuse)?;
    let canvas = StrokeCanvas::for_profile(&pen1, 128);
    let mut sheet = Compositor::new(128 * 5, 128, canvas.px_per_mm);
    for (i, m) in ModelKind::ALL.iter().enumerate() {
        let a = canvas.anchor_mm(&fp, press.beta_rad);
        let anchor = brush_model::PointMm::new(a.x_mm + i as f64 * canvas.size_mm(), a.y_mm);
        sheet.stamp(m.model(), &Stamp { footprint: fp, anchor, beta_rad: press.beta_rad });
    }
    Ok(sheet.image().encode_png()?)
}

fn character_render(ch: char, method: trajectory::Method) -> Result<Vec<u8>> {
    use pipeline::{BoxRule, WriteOptions, prepare, write_placed};
    let pen1 = BrushProfile::builtin("pen1")?;
    let p = prepare(trajectory::embedded_glyph(ch)?, Some(method))?;
    let opts = WriteOptions { size: 256, free_widths: false, ..WriteOptions::default() };
    let r = write_placed(&p, &pen1, &opts, BoxRule::Auto)?;
    Ok(r.render.encode_png()?)
}

fn python_ready() -> bool {
    std::process::Command::new("python3")
        .args(["-c", "import numpy, skimage, statsmodels"])
        .output()
        .is_ok_and(|o| o.status.success())
}

fn python_golden(dir: &str, script: &str) -> Result<Vec<u8>> {
    let out = std::process::Command::new("python3")
        .arg(script)
        .current_dir(root().join(dir))
        .output()
        .with_context(|| format!("running python3 {script}"))?;
    if !out.status.success() {
        anyhow::bail!("python3 {script} failed: {}", String::from_utf8_lossy(&out.stderr));
    }
    Ok(out.stdout)
}

/// The folder holding the character files: `--hanzi-data DIR` itself or the first of its
/// subfolders (`package/`, as `npm pack hanzi-writer-data` unpacks, or `data/`) that has
/// `一.json`.
fn hanzi_dir(i: &Inputs) -> Result<PathBuf> {
    let dir = i.hanzi_data.as_deref().context("needs --hanzi-data DIR (an unpacked `npm pack hanzi-writer-data`)")?;
    trajectory::HANZI_SUBFOLDERS
        .iter()
        .map(|sub| if sub.is_empty() { dir.to_path_buf() } else { dir.join(sub) })
        .find(|d| d.join("一.json").is_file())
        .with_context(|| {
            format!(
                "{}: no hanzi-writer-data character files (一.json) in it or its package/ or data/ folder",
                dir.display()
            )
        })
}

/// The characters of the frequency subset: the 1,000 most frequent, then [`EXTRA_CHARS`].
fn subset_chars() -> Result<Vec<char>> {
    let freq = std::fs::read_to_string(root().join("fixtures/hanzi/frequency.txt"))?;
    let mut chars: Vec<char> =
        freq.lines().filter(|l| !l.starts_with('#')).filter_map(|l| l.chars().next()).take(1000).collect();
    for c in EXTRA_CHARS.chars() {
        if !chars.contains(&c) {
            chars.push(c);
        }
    }
    Ok(chars)
}

/// Every `<char>.json` of the package (one character in the name), packed by
/// `trajectory::pack_hanzi` with the subset's order.
fn hanzi_blob(i: &Inputs) -> Result<Vec<u8>> {
    let dir = hanzi_dir(i)?;
    let mut files = Vec::new();
    for entry in std::fs::read_dir(&dir).with_context(|| format!("reading {}", dir.display()))? {
        let path = entry?.path();
        let Some(name) = path.file_name().and_then(|n| n.to_str()) else { continue };
        let Some(stem) = name.strip_suffix(".json") else { continue };
        let mut cs = stem.chars();
        let (Some(c), None) = (cs.next(), cs.next()) else { continue };
        let text = std::fs::read_to_string(&path).with_context(|| format!("reading {}", path.display()))?;
        files.push((c, text));
    }
    files.sort_by_key(|f| f.0);
    Ok(trajectory::pack_hanzi(&files, &subset_chars()?)?)
}

/// One minified line per character: `{"c":"永","strokes":[...],"medians":[...]}`, in frequency
/// order, then the extra characters.
fn hanzi_subset(i: &Inputs) -> Result<Vec<u8>> {
    let dir = hanzi_dir(i)?;
    let mut out = String::new();
    for c in subset_chars()? {
        let path = dir.join(format!("{c}.json"));
        let text = std::fs::read_to_string(&path).with_context(|| format!("reading {}", path.display()))?;
        let v: serde_json::Value =
            serde_json::from_str(&text).with_context(|| format!("parsing {}", path.display()))?;
        let line = serde_json::json!({"c": c.to_string(), "strokes": v["strokes"], "medians": v["medians"]});
        out.push_str(&serde_json::to_string(&line)?);
        out.push('\n');
    }
    Ok(out.into_bytes())
}

/// The repository root (xtask's parent folder).
pub fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).parent().expect("xtask has a parent").to_path_buf()
}

pub fn run(args: &[String]) -> Result<()> {
    let mut check = false;
    let mut only: Option<String> = None;
    let mut inputs = Inputs { hanzi_data: None, write_extra: false };
    let mut it = args.iter();
    while let Some(a) = it.next() {
        match a.as_str() {
            "--check" => check = true,
            "--hanzi-data" => inputs.hanzi_data = Some(it.next().context("--hanzi-data needs a folder")?.into()),
            "--only" => only = Some(it.next().context("--only needs part of a fixture's path")?.clone()),
            other => {
                anyhow::bail!("fixtures: unknown argument `{other}` (expected --check, --hanzi-data DIR, --only TEXT)")
            }
        }
    }
    let root = root();
    println!(
        "skipped  crates/neural-gen/data/pen1.safetensors  (made by `cargo xtask train-fixture`, about 5 minutes; checked by the generator gates)"
    );
    let mut differ = Vec::new();
    let python = python_ready();
    inputs.write_extra = !check;
    for f in all() {
        if only.as_ref().is_some_and(|o| !f.path.contains(o.as_str())) {
            continue;
        }
        if f.needs_python && !python {
            println!("skipped  {}  (needs python3 with numpy, scikit-image, statsmodels)", f.path);
            continue;
        }
        if f.needs_hanzi && inputs.hanzi_data.is_none() {
            if check && f.path.ends_with("hanzi.bin") {
                // Not regenerable offline, but checkable: its hash, index and every character.
                let n = trajectory::verify_embedded().context(f.path)?;
                println!(
                    "ok       {}  (offline: hash, index and all {n} characters decode; regenerated only with --hanzi-data DIR)",
                    f.path
                );
                continue;
            }
            println!("skipped  {}  (needs --hanzi-data DIR; not regenerable offline)", f.path);
            continue;
        }
        let bytes = (f.generate)(&inputs).with_context(|| format!("generating {}", f.path))?;
        let path = root.join(f.path);
        if check {
            match std::fs::read(&path) {
                Ok(old) if old == bytes => println!("ok       {}", f.path),
                Ok(_) => {
                    println!("DIFFERS  {}", f.path);
                    differ.push(f.path);
                }
                Err(_) => {
                    println!("MISSING  {}", f.path);
                    differ.push(f.path);
                }
            }
        } else {
            std::fs::create_dir_all(path.parent().expect("fixture has a folder"))?;
            std::fs::write(&path, &bytes).with_context(|| format!("writing {}", path.display()))?;
            println!("wrote    {}  ({})", f.path, f.about);
        }
    }
    if !differ.is_empty() {
        anyhow::bail!(
            "{} fixture(s) differ from what the generators produce now: {}; run `cargo xtask fixtures` and review the diff",
            differ.len(),
            differ.join(", ")
        );
    }
    Ok(())
}

fn sample_measurements() -> Result<Vec<u8>> {
    let pen1 = BrushProfile::builtin("pen1")?;
    let mut rng = SplitMix(0x6d61_6f62_6931);
    let mut s = String::from("h_mm,alpha_deg,beta_deg,lt_mm,lh_mm,lr_mm\n");
    for h in [11.0, 13.0, 15.0, 17.0, 20.0] {
        for a in [0.0, 5.0, 10.0] {
            for b in [0.0, 5.0] {
                for _ in 0..3 {
                    let f = pen1.predict(&Press::from_degrees(h, a, b), Extrapolation::Refuse)?;
                    let mut noisy = |v: f64| v + 0.15 * rng.normal();
                    let (lt, lh, lr) = (noisy(f.lt_mm), noisy(f.lh_mm), noisy(f.lr_mm));
                    s.push_str(&format!("{h},{a},{b},{lt:.3},{lh:.3},{lr:.3}\n"));
                }
            }
        }
    }
    Ok(s.into_bytes())
}
