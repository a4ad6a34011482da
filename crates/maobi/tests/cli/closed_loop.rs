//! The closed loop against the test world (`common::world`): a sheet written, inked by a brush
//! that writes wider, longer, with its hairs lagging, trailing less and turning only under a
//! press, and its ink spreading, photographed,
//! observed, and written again with `--observed` (the brush re-fitted and the tracks refined
//! against the glyph shifted by the observed residual; with `--brush-only` the brush alone),
//! twice. Scored by the
//! CSIM of the world's ink against the glyph, on characters not used to tune the loop (the
//! loop's constants were tried on 中国; these are 山水, and 天心山 for the full figures).

use std::path::{Path, PathBuf};

use bezier_raster::Coverage;

use crate::common::world::*;
use crate::common::{fails, maobi, ok, s};

/// The characters of the fast test (not used to tune the loop).
const CHARS: &str = "山水";
/// The characters of the full measurement (`closed_loop_figures`, ignored).
const FULL_CHARS: &str = "天心山";

/// What one chain of rounds measured: the world's ink against the glyph per round (mean CSIM
/// over the characters), the world-equals-model baseline, and each round's folders.
struct Chain {
    csim: Vec<f64>,
    per_char: Vec<Vec<f64>>,
    baseline: f64,
    sheets: Vec<PathBuf>,
    observed: Vec<PathBuf>,
}

struct Setup<'a> {
    chars: &'a str,
    size: u32,
    photo: [usize; 2],
    focal_px: f64,
    /// How the world writes with a brush (the built-in in the robot).
    world: fn(&brush_model::BrushProfile) -> WorldBrush,
}

/// The test world, the same for every brush.
fn same_world(_: &brush_model::BrushProfile) -> WorldBrush {
    WORLD
}

/// A world whose departure from the profile differs between brushes: the brushes smaller than
/// pen1 (radius under 6 mm, the ones a round picks) write only 8 % wider and 5 % longer than
/// their profiles (pen1: 18 % and 12 %); lag, trail and spread as [`WORLD`]. Carrying pen1's
/// correction over to them over-corrects them.
fn world_by_brush(truth: &brush_model::BrushProfile) -> WorldBrush {
    if truth.brush.radius_mm < 6.0 { WorldBrush { width: 1.08, length: 1.05, ..WORLD } } else { WORLD }
}

/// A world whose hairs need 3 mm of press to turn: more than the nominal profile says (1 mm) and
/// than the planner's glides give it (2 mm), so the first attempt leaves wedges that the brush
/// fit must explain with a contact depth (`MAOBI_LOOP_WORLD=stiff`).
fn stiff_world(_: &brush_model::BrushProfile) -> WorldBrush {
    WorldBrush { contact_h_mm: 3.0, ..WORLD }
}

const FAST: Setup<'static> =
    Setup { chars: CHARS, size: 128, photo: [1200, 1620], focal_px: 1410.0, world: same_world };

/// The world's ink of each character of `sheet` (its commanded strokes, the brush `truth` the
/// world really has) against its reference glyph: CSIM per character.
fn world_csim(sheet: &Path, truth: &brush_model::BrushProfile, w: &WorldBrush) -> Vec<f64> {
    let track = robot_io::TrackFile::load(&sheet.join("track.json")).unwrap();
    let st = json(&sheet.join("track.json"));
    let stamps = world_stamps_with(&track.strokes, truth, w);
    st["chars"]
        .as_array()
        .unwrap()
        .iter()
        .enumerate()
        .map(|(i, c)| {
            let name = format!("{:02}-{}", i + 1, c["char"].as_str().unwrap());
            let reference = Coverage::load(&sheet.join(&name).join("reference.png")).unwrap();
            let b: Vec<f64> = c["char_box_mm"].as_array().unwrap().iter().map(|v| v.as_f64().unwrap()).collect();
            let ink = world_ink(&stamps, [b[0], b[1], b[2]], reference.width());
            stroke_metrics::csim(reference.as_gray(), ink.as_gray()).unwrap()
        })
        .collect()
}

/// The brush in the robot when `sheet` was written: the built-in its profile was derived from
/// (a corrected profile is named `<built-in>+observedN`; when a round picks another brush, the
/// user puts that one in). The world writes with it times the world's factors.
fn robot_brush(sheet: &Path) -> brush_model::BrushProfile {
    let named = robot_io::TrackFile::load(&sheet.join("track.json")).unwrap().brush.name;
    brush_model::BrushProfile::builtin(named.split('+').next().unwrap()).unwrap()
}

fn mean(v: &[f64]) -> f64 {
    v.iter().sum::<f64>() / v.len() as f64
}

/// How a chain's tracks are made.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Tracks {
    /// The first attempt unrefined; the rounds use both levers (the brush, the ILC refinement).
    Unrefined,
    /// Unrefined throughout: the rounds correct the brush only (`--brush-only`).
    BrushOnly,
    /// Every attempt refined (`--refine`).
    Refined,
}

impl Tracks {
    fn tag(self) -> &'static str {
        match self {
            Tracks::Unrefined => "unrefined",
            Tracks::BrushOnly => "brush-only",
            Tracks::Refined => "refined",
        }
    }
}

/// Writes `setup.chars` on A4, then `rounds` times: the world inks it, the camera photographs
/// it, `observe` looks at it and `write --observed` writes it again.
fn chain(dir: &Path, setup: &Setup<'_>, tracks: Tracks, rounds: usize) -> Chain {
    let tag = tracks.tag();
    let size = setup.size.to_string();
    let write = |out: &Path, observed: Option<&Path>| {
        let mut a = vec!["write", setup.chars, "--sheet", "A4", "--size", &size, "-o", s(out)];
        if tracks == Tracks::Refined {
            a.push("--refine");
        }
        if let Some(o) = observed {
            a.extend(["--observed", s(o)]);
            if tracks == Tracks::BrushOnly {
                a.push("--brush-only");
            }
        }
        let stdout = ok(&maobi(&a));
        eprintln!("{}", stdout.lines().last().unwrap_or(""));
    };
    let first = dir.join(format!("{tag}-0"));
    write(&first, None);
    // The world's brush is the built-in each sheet was written for (the first sheet's, or the
    // one a round picked); the corrected profiles only change what is commanded.
    let truth = robot_brush(&first);
    let mut chain = Chain {
        csim: Vec::new(),
        per_char: Vec::new(),
        baseline: mean(&world_csim(&first, &truth, &MODEL_WORLD)),
        sheets: vec![first],
        observed: Vec::new(),
    };
    let mut rng = Rng(2028);
    for k in 0..=rounds {
        let sheet = chain.sheets[k].clone();
        let truth = robot_brush(&sheet);
        let per = world_csim(&sheet, &truth, &(setup.world)(&truth));
        chain.csim.push(mean(&per));
        chain.per_char.push(per);
        if k == rounds {
            break;
        }
        let track = robot_io::TrackFile::load(&sheet.join("track.json")).unwrap();
        let stamps = world_stamps_with(&track.strokes, &truth, &(setup.world)(&truth));
        let cam = random_camera(&mut rng, 0.0);
        let (jpeg, _) = photograph_sized(&stamps, [210.0, 297.0], &cam, 40 + k as u64, setup.photo, setup.focal_px);
        let photo = dir.join(format!("{tag}-photo{k}.jpg"));
        std::fs::write(&photo, &jpeg).unwrap();
        let seen = dir.join(format!("{tag}-seen{k}"));
        ok(&maobi(&["observe", s(&photo), "--sheet", s(&sheet), "-o", s(&seen)]));
        let next = dir.join(format!("{tag}-{}", k + 1));
        write(&next, Some(&seen));
        chain.observed.push(seen);
        chain.sheets.push(next);
    }
    eprintln!(
        "{tag} {}: world CSIM vs glyph per round {:?} (per char {:?}); world == model {:.4}; brushes {:?}",
        setup.chars,
        chain.csim.iter().map(|v| format!("{v:.4}")).collect::<Vec<_>>(),
        chain.per_char,
        chain.baseline,
        chain
            .sheets
            .iter()
            .map(|d| robot_io::TrackFile::load(&d.join("track.json")).unwrap().brush.name)
            .collect::<Vec<_>>()
    );
    chain
}

/// Runs two rounds and checks what every chain must show.
fn two_rounds(tracks: Tracks) {
    let dir = tempfile::tempdir().unwrap();
    let dir = dir.path();
    let dir = &std::env::var_os("MAOBI_LOOP_KEEP").map_or(dir.to_path_buf(), PathBuf::from);
    let c = chain(dir, &FAST, tracks, 2);
    // The gain over two rounds (the target: 0.04), the second round no worse than the
    // first (converged), and the end within 0.01 of the first attempt's score when the world
    // equals the model (the second target).
    let gain = c.csim[2] - c.csim[0];
    assert!(gain >= 0.04, "{tracks:?}: CSIM {:?}: gain {gain}", c.csim);
    assert!(c.csim[2] >= c.csim[1] - 0.005, "{tracks:?}: CSIM {:?}", c.csim);
    assert!(c.csim[2] >= c.baseline - 0.01, "{tracks:?}: CSIM {:?}, world = model {}", c.csim, c.baseline);
    // Each round's figures, from the observed summaries, in the last sheet's summary.
    let summary = json(&c.sheets[2].join("summary.json"));
    let rounds = summary["rounds"].as_array().unwrap();
    assert_eq!(rounds.len(), 2, "{summary}");
    for (k, r) in rounds.iter().enumerate() {
        assert_eq!(r["round"], k);
        let seen = json(&c.observed[k].join("summary.json"));
        assert_eq!(r["chars"][0]["vs_glyph"], seen["chars"][0]["vs_glyph"]);
        // The hairs are fitted among the brush's corrections and carried in its profile: the
        // world's need for 1 mm of press cannot be told from the nominal 1 mm on a sheet whose
        // glides press 2 mm, so the nominal depth is kept.
        let hairs = &r["correction"]["hairs"];
        assert_eq!(hairs["contact_h_mm"], serde_json::json!(brush_model::CONTACT_H_MM), "{r}");
        assert_eq!(json(&c.sheets[k + 1].join("brush.json"))["hairs"], *hairs, "{r}");
    }
    // The first correction sees the world's wider, longer brush; the second changes the ink
    // far less.
    let corr = |k: usize, f: &str| rounds[k]["correction"][f].as_f64().unwrap();
    assert!(corr(0, "width_factor") > 1.08 && corr(0, "length_factor") > 1.04, "{}", rounds[0]);
    // The corrected brush writes wider than its profile said: the first correction writes the
    // next attempt with a smaller built-in (the one whose corrected footprints suit the box),
    // and says why; the second keeps it.
    let radius_mm = |n: &str| brush_model::BrushProfile::builtin(n.split('+').next().unwrap()).unwrap().brush.radius_mm;
    let brush = |k: usize, f: &str| rounds[k][f].as_str().unwrap().to_string();
    assert!(radius_mm(&brush(0, "brush_after")) < radius_mm(&brush(0, "brush")), "{}", rounds[0]);
    assert_eq!(rounds[0]["brush_choice"]["name"].as_str(), Some(brush(0, "brush_after").as_str()));
    assert!(rounds[0]["brush_choice"]["reason"].as_str().unwrap().contains("corrected from the photo"));
    assert_eq!(brush(1, "brush_after"), brush(0, "brush_after"), "{}", rounds[1]);
    // Both levers (the first attempt refined or not): the round that keeps the brush refines
    // from the last attempt's track; the round that changed it rebuilt the track.
    let from_last = |k: usize| rounds[k]["track"].as_str().unwrap().contains("from the last attempt's track");
    assert_eq!((from_last(0), from_last(1)), (false, true), "{} / {}", rounds[0]["track"], rounds[1]["track"]);
    let drop = |k: usize| corr(k, "ink_error_before") - corr(k, "ink_error_after");
    assert!(drop(1) < 0.25 * drop(0), "{} then {}", rounds[0]["correction"], rounds[1]["correction"]);
    eprintln!("{tracks:?}: corrections {} then {}", rounds[0]["correction"], rounds[1]["correction"]);
    // The corrected profile is a brush file `--brush` takes.
    let brush = c.sheets[1].join("brush.json");
    ok(&maobi(&[
        "write",
        "十",
        "--size",
        "64",
        "--brush",
        s(&brush),
        "-o",
        s(&dir.join(format!("b{}", tracks.tag()))),
    ]));
    let report = json(&c.sheets[1].join("01-山").join("report.json"));
    assert!(report["refine"].is_object(), "{report}");
    if tracks == Tracks::Unrefined {
        let size = FAST.size.to_string();
        let rewrite = |seen: &Path, extra: &[&str], out: &Path| {
            let mut a =
                vec!["write", FAST.chars, "--sheet", "A4", "--size", &size, "--observed", s(seen), "-o", s(out)];
            a.extend(extra);
            maobi(&a)
        };
        // --brush-only: the same round with the brush lever alone builds the tracks, refines
        // nothing, and says so.
        let only = dir.join("brush-only");
        ok(&rewrite(&c.observed[0], &["--brush-only"], &only));
        let report = json(&only.join("01-山").join("report.json"));
        assert!(report["refine"].is_null(), "{report}");
        let round = &json(&only.join("summary.json"))["rounds"][0];
        assert_eq!(round["track"], "built with the corrected brush", "{round}");
        assert_eq!(round["brush_after"], rounds[0]["brush_after"], "{round}");
        fails(&maobi(&["write", FAST.chars, "--sheet", "A4", "--brush-only", "-o", s(&only)]), "--observed");
        // The corrected sheet's track carries the brush as fitted, its hairs included; a
        // damaged trailing reach there is refused by name, and nothing is written.
        let sheet_track = c.sheets[1].join("track.json");
        let mut damaged = json(&sheet_track);
        assert_eq!(damaged["brush"]["hairs"], json(&c.sheets[1].join("brush.json"))["hairs"]);
        damaged["brush"]["hairs"]["trail_reach"] = serde_json::json!(7.5);
        std::fs::write(&sheet_track, damaged.to_string()).unwrap();
        let out = dir.join("damaged");
        fails(&rewrite(&c.observed[1], &[], &out), "hairs.trail_reach");
        assert!(!out.exists());
    }
}

#[test]
fn two_rounds_bring_the_world_ink_of_unrefined_tracks_to_the_glyph() {
    two_rounds(Tracks::Unrefined);
}

#[test]
fn two_rounds_bring_the_world_ink_of_refined_tracks_to_the_glyph() {
    two_rounds(Tracks::Refined);
}

#[test]
fn write_observed_refuses_another_sheet() {
    let dir = tempfile::tempdir().unwrap();
    let sheet = dir.path().join("sheet");
    ok(&maobi(&["write", "十口", "--sheet", "A5", "--size", "64", "-o", s(&sheet)]));
    // A stand-in for observe's output (a valid observation of the sheet, no images): what
    // write reads before refusing.
    let seen = dir.path().join("seen");
    std::fs::create_dir_all(&seen).unwrap();
    let scores = serde_json::json!({"csim": 0.9, "ssim": 0.8, "iou": 0.8});
    let diagnosis = serde_json::json!({"strokes": [], "width_ratio": null, "end_beyond_mm": null, "lateral_mm": null});
    let chars: Vec<serde_json::Value> = ["十", "口"]
        .iter()
        .enumerate()
        .map(|(i, c)| {
            serde_json::json!({"char": c, "folder": pipeline::char_folder(i, c), "size_px": 64, "vs_glyph": scores,
                "vs_plan": scores, "diagnosis": diagnosis, "verdict": ""})
        })
        .collect();
    let summary = serde_json::json!({
        "version": pipeline::OBSERVATION_VERSION, "photo": "photo.jpg", "text": "十口", "brush": "pen1",
        "sheet": {
            "path": std::fs::canonicalize(&sheet).unwrap(),
            "track_fingerprint": pipeline::fingerprint(&std::fs::read(sheet.join("track.json")).unwrap()),
        },
        "registration": {"residual_rms_mm": 0.0, "residual_max_mm": 0.0, "leave_one_out_max_mm": 0.0, "edge_mm": 0.3,
            "photo_px_per_mm": 6.0, "photo_reduced_by": 1, "corner_shift": 0, "lens_distortion": "not modelled",
            "paper_to_photo": {"m": [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]}, "marks": []},
        "chars": chars,
    });
    std::fs::write(seen.join("summary.json"), summary.to_string()).unwrap();
    let out = dir.path().join("out");
    fails(
        &maobi(&["write", "口十", "--sheet", "A5", "--size", "64", "--observed", s(&seen), "-o", s(&out)]),
        "give the same characters",
    );
    fails(
        &maobi(&["write", "十口", "--sheet", "A4", "--size", "64", "--observed", s(&seen), "-o", s(&out)]),
        "laid out otherwise",
    );
    fails(
        &maobi(&["write", "十口", "--sheet", "A5", "--size", "64", "--observed", s(&seen), "-o", s(&out)]),
        "observed.png",
    );
    assert!(!out.exists());
    let none = dir.path().join("none");
    fails(
        &maobi(&["write", "十口", "--sheet", "A5", "--size", "64", "--observed", s(&none), "-o", s(&out)]),
        "summary.json",
    );
}

/// The full figures for docs/closed-loop.md: 天心山 at 256 px with the full-size photo, two
/// rounds, unrefined and refined; with `MAOBI_LOOP_IMAGES=DIR`, glyph | first attempt | round 1
/// | round 2 of the world's ink per chain as PNGs in DIR.
/// `cargo test -p maobi --test cli -- closed_loop::closed_loop_figures --ignored --nocapture`.
#[test]
#[ignore = "slow: the full figures for docs/closed-loop.md"]
fn closed_loop_figures() {
    let dir = tempfile::tempdir().unwrap();
    let dir = dir.path();
    let dir = &std::env::var_os("MAOBI_LOOP_KEEP").map_or(dir.to_path_buf(), PathBuf::from);
    // `MAOBI_LOOP_CHARS` takes other characters (the tuning set, 中国, when trying a change).
    let chars = std::env::var("MAOBI_LOOP_CHARS").unwrap_or_else(|_| FULL_CHARS.to_string());
    // `MAOBI_LOOP_WORLD=by-brush`: the world of [`world_by_brush`]; `stiff`: [`stiff_world`].
    let world = match std::env::var("MAOBI_LOOP_WORLD").as_deref() {
        Ok("by-brush") => world_by_brush,
        Ok("stiff") => stiff_world,
        _ => same_world,
    };
    let full = Setup { chars: &chars, size: 256, photo: [PHOTO_W, PHOTO_H], focal_px: FOCAL_PX, world };
    for tracks in [Tracks::Unrefined, Tracks::BrushOnly, Tracks::Refined] {
        let c = chain(dir, &full, tracks, 2);
        let summary = json(&c.sheets[2].join("summary.json"));
        for r in summary["rounds"].as_array().unwrap() {
            eprintln!(
                "round {}: observed CSIM vs glyph {}; correction {}",
                r["round"], r["observed_vs_glyph_mean"]["csim"], r["correction"]
            );
        }
        // The corrected profiles' footprints against the world's over the press range.
        for k in 1..=2 {
            let truth = robot_brush(&c.sheets[k]);
            let fitted = brush_model::BrushProfile::load(&c.sheets[k].join("brush.json")).unwrap();
            let w = (full.world)(&truth);
            for f in [0.0, 0.5, 1.0] {
                let h = truth.ranges.h_mm.lerp(f);
                let press = brush_model::Press::new(h, 0.0, 0.0);
                let t = truth.predict(&press, brush_model::Extrapolation::Refuse).unwrap();
                let g = fitted.predict(&press, brush_model::Extrapolation::Refuse).unwrap();
                eprintln!(
                    "brush after round {k}, h {h:.2} mm: lt {:.2} (world {:.2}), lh {:.2} (world {:.2}), lr {:.2} (world {:.2}); profile {:.2}/{:.2}/{:.2} mm",
                    g.lt_mm,
                    w.length * t.lt_mm + w.spread_mm,
                    g.lh_mm,
                    w.length * t.lh_mm + w.spread_mm,
                    g.lr_mm,
                    w.width * t.lr_mm + w.spread_mm,
                    t.lt_mm,
                    t.lh_mm,
                    t.lr_mm
                );
            }
        }
        if let Some(out) = std::env::var_os("MAOBI_LOOP_IMAGES") {
            let out = PathBuf::from(out);
            std::fs::create_dir_all(&out).unwrap();
            let st = json(&c.sheets[0].join("track.json"));
            let mut rows = Vec::new();
            for (i, ch) in st["chars"].as_array().unwrap().iter().enumerate() {
                let name = format!("{:02}-{}", i + 1, ch["char"].as_str().unwrap());
                let b: Vec<f64> = ch["char_box_mm"].as_array().unwrap().iter().map(|v| v.as_f64().unwrap()).collect();
                let mut row = vec![Coverage::load(&c.sheets[0].join(&name).join("reference.png")).unwrap()];
                for sheet in &c.sheets {
                    let t = robot_io::TrackFile::load(&sheet.join("track.json")).unwrap();
                    let truth = robot_brush(sheet);
                    let stamps = world_stamps_with(&t.strokes, &truth, &(full.world)(&truth));
                    row.push(world_ink(&stamps, [b[0], b[1], b[2]], full.size));
                }
                rows.push(pipeline::side_by_side(&row.iter().collect::<Vec<_>>()));
            }
            // One row per character, stacked.
            let (w, h) = (rows[0].width(), rows.iter().map(|r| r.height() + 4).sum::<u32>() - 4);
            let mut img = Coverage::new(w, h);
            let mut y0 = 0usize;
            for r in &rows {
                let n = (r.width() * r.height()) as usize;
                img.data_mut()[y0 * w as usize..y0 * w as usize + n].copy_from_slice(r.data());
                y0 += r.height() as usize + 4;
            }
            std::fs::write(out.join(format!("closed-loop-{}.png", tracks.tag())), img.encode_png().unwrap()).unwrap();
        }
    }
}

/// Which of the world's differences costs the first attempt what (docs/closed-loop.md): the
/// refined first attempt of 天心山 (256 px) inked by the world, by the world with one
/// difference taken out, and by the model's world with one put in; world CSIM per character.
/// With `MAOBI_LOOP_IMAGES=DIR`, 山's ink under each as `world-<variant>.png`.
/// `cargo test -p maobi --test cli -- closed_loop::what_each_world_difference_costs --ignored --nocapture`.
#[test]
#[ignore = "slow: a measurement for docs/closed-loop.md"]
fn what_each_world_difference_costs() {
    let dir = tempfile::tempdir().unwrap();
    // `MAOBI_LOOP_SHEET=DIR` measures a sheet already written (a round of `closed_loop_figures`
    // kept with `MAOBI_LOOP_KEEP`).
    let sheet = match std::env::var_os("MAOBI_LOOP_SHEET") {
        Some(d) => PathBuf::from(d),
        None => {
            let sheet = dir.path().join("sheet");
            ok(&maobi(&["write", FULL_CHARS, "--sheet", "A4", "--size", "256", "--refine", "-o", s(&sheet)]));
            sheet
        }
    };
    let truth = robot_brush(&sheet);
    let variants = [
        ("world", WORLD),
        ("world-trail-0.5", WorldBrush { trail_reach: 0.5, ..WORLD }),
        ("world-lag-0", WorldBrush { lag_mm: 0.0, ..WORLD }),
        ("world-spread-0", WorldBrush { spread_mm: 0.0, ..WORLD }),
        ("model", MODEL_WORLD),
        ("model-trail-0.3", WorldBrush { trail_reach: WORLD_TRAIL_REACH, ..MODEL_WORLD }),
        ("model-lag-0.4", WorldBrush { lag_mm: WORLD_LAG_MM, ..MODEL_WORLD }),
    ];
    let track = robot_io::TrackFile::load(&sheet.join("track.json")).unwrap();
    let st = json(&sheet.join("track.json"));
    let out = std::env::var_os("MAOBI_LOOP_IMAGES").map(PathBuf::from);
    for (name, w) in variants {
        let per = world_csim(&sheet, &truth, &w);
        eprintln!("{name}: world CSIM per character {per:.4?}, mean {:.4}", mean(&per));
        if let Some(out) = &out {
            std::fs::create_dir_all(out).unwrap();
            let stamps = world_stamps_with(&track.strokes, &truth, &w);
            let ch = st["chars"].as_array().unwrap().last().unwrap();
            let b: Vec<f64> = ch["char_box_mm"].as_array().unwrap().iter().map(|v| v.as_f64().unwrap()).collect();
            let ink = world_ink(&stamps, [b[0], b[1], b[2]], 256);
            std::fs::write(out.join(format!("world-{name}.png")), ink.encode_png().unwrap()).unwrap();
        }
    }
}
