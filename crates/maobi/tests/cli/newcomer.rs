//! What a newcomer meets first: help without a subcommand, typo tips, spaces in the text,
//! `evaluate`'s table, which generator weights were scored.

use crate::common::{maobi, ok, s};

fn stderr(o: &std::process::Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

#[test]
fn no_subcommand_prints_the_wrapped_help() {
    for args in [&[][..], &["robot"][..]] {
        let o = maobi(args);
        assert_eq!(o.status.code(), Some(2), "{args:?}");
        let e = stderr(&o);
        assert!(e.contains("Usage: maobi") && e.contains("Commands:"), "{args:?}: {e}");
        assert!(e.lines().count() > 8, "{args:?}: the help on several lines: {e}");
        assert!(e.lines().all(|l| l.chars().count() <= 200), "{args:?}: wrapped: {e}");
    }
}

#[test]
fn a_typo_gets_its_tip_on_the_one_error_line() {
    let o = maobi(&["wirte", "永"]);
    assert_eq!(o.status.code(), Some(2));
    let e = stderr(&o);
    assert_eq!(e.trim_end().lines().count(), 1, "{e}");
    assert!(e.contains("'wirte' (tip: a similar subcommand exists: 'write')"), "{e}");
}

#[test]
fn a_space_in_the_text_is_said_to_be_left_out() {
    let dir = tempfile::tempdir().unwrap();
    let o = maobi(&["write", "十 口", "--size", "64", "-o", s(&dir.path().join("w"))]);
    ok(&o);
    assert!(stderr(&o).contains("TEXT has 1 space(s)"), "{}", stderr(&o));
    assert!(dir.path().join("w/02-口").is_dir());
    // The default robot.json has no ink pot: the preview says dipping is off, not "0 dips".
    let page = std::fs::read_to_string(dir.path().join("w/preview.html")).unwrap();
    assert!(page.contains("ink dipping off") && page.contains("robot-ink.json"), "the preview names the ink switch");
}

#[test]
fn evaluate_prints_a_row_per_character_and_the_means_last() {
    let out = ok(&maobi(&["evaluate", "--chars", "十口", "--size", "64"]));
    let lines: Vec<&str> = out.lines().collect();
    let head = lines.iter().position(|l| l.starts_with("char")).expect("a table header");
    assert!(lines[head].contains("exec CSIM"), "{out}");
    assert!(lines[head + 1].starts_with('十') && lines[head + 2].starts_with('口'), "{out}");
    let mean = lines[head + 3];
    assert!(mean.starts_with("mean"), "{out}");
    // The mean row's plan CSIM is the mean of the rows'.
    let plan = |l: &str| l.split_whitespace().nth(2).unwrap().parse::<f64>().unwrap();
    let m = (plan(lines[head + 1]) + plan(lines[head + 2])) / 2.0;
    assert!((plan(mean) - m).abs() < 1e-4, "{out}");
    let help = ok(&maobi(&["evaluate", "--help"]));
    for absent in ["--sheet", "--image ", "write's report.json"] {
        assert!(!help.contains(absent), "evaluate --help mentions {absent}: {help}");
    }
}

#[test]
fn a_font_glyph_is_placed_by_its_ink_box_not_cut_off() {
    // Ma Shan Zheng's 永 reaches below the em box hanzi-writer-data assumes: it was cut off at
    // the bottom of reference.png, render.png and executed.png.
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("msz");
    let font = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/fonts/msz");
    ok(&maobi(&["write", "永", "--font", s(&font), "--size", "128", "-o", s(&out)]));
    let g = image::open(out.join("reference.png")).unwrap().to_luma8();
    let inked: Vec<u32> = (0..g.height()).filter(|&y| (0..g.width()).any(|x| g.get_pixel(x, y)[0] < 128)).collect();
    let (top, bottom) = (inked[0], *inked.last().unwrap());
    assert!(bottom < g.height() - 1 && top > 0, "ink rows {top}..={bottom} touch the edge");
    // Centred: as far from the top as from the bottom (to a pixel or two).
    let (above, below) = (top as i64, (g.height() - 1 - bottom) as i64);
    assert!((above - below).abs() <= 2, "{above} px above, {below} px below");
    // The whole glyph reaches the plan: every template stroke is there.
    let r: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("report.json")).unwrap()).unwrap();
    assert_eq!(r["plan"]["strokes_found"], 5, "{r}");
}

#[test]
fn a_sheet_gets_a_brush_that_fits_and_the_summary_says_which() {
    let dir = tempfile::tempdir().unwrap();
    let json = |p: &std::path::Path| -> serde_json::Value {
        serde_json::from_str(&std::fs::read_to_string(p).unwrap()).unwrap()
    };
    // The README's first sheet: pen1 is too wide for 85.7 mm boxes.
    let p1 = dir.path().join("pen1");
    ok(&maobi(&["write", "永字八法", "--sheet", "A4", "--size", "64", "--brush", "pen1", "-o", s(&p1)]));
    let s1 = json(&p1.join("summary.json"));
    assert_eq!(s1["brush_fit"]["covered"], false, "{}", s1["brush_fit"]);
    assert!(s1["brush_choice"].is_null());
    // By default a sheet gets the built-in whose width range suits its box size, and says why.
    let auto = dir.path().join("auto");
    let said = ok(&maobi(&["write", "永字八法", "--sheet", "A4", "--size", "64", "-o", s(&auto)]));
    let sum = json(&auto.join("summary.json"));
    let name = sum["brush_choice"]["name"].as_str().unwrap().to_string();
    assert!(name != "pen1", "{}", sum["brush_choice"]);
    assert_eq!(sum["brush"], name.as_str());
    assert_eq!(sum["brush_fit"]["covered"], true, "{}", sum["brush_fit"]);
    assert!(said.contains(&format!("brush (--brush auto): {name}")), "{said}");
    let (box_mm, suits) = (sum["char_mm"].as_f64().unwrap(), sum["brush_choice"]["brush_char_mm"].as_f64().unwrap());
    assert!((suits / box_mm).ln().abs() < 1.19f64.ln(), "{suits} mm for a {box_mm} mm box");
    // The track records the brush the robot must hold.
    assert_eq!(json(&auto.join("track.json"))["brush"]["name"], name.as_str());
}

/// A run's report.json.
fn report(dir: &std::path::Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(dir.join("report.json")).unwrap()).unwrap()
}

#[test]
fn characters_beyond_the_frequent_thousand_write_without_flags() {
    let dir = tempfile::tempdir().unwrap();
    for (c, strokes) in [("眠", 10), ("龍", 16)] {
        let out = dir.path().join(c);
        ok(&maobi(&["write", c, "--size", "64", "-o", s(&out)]));
        let r = report(&out);
        assert_eq!(r["source"], "embedded", "{c}: {r}");
        assert_eq!(r["plan"]["strokes_found"], strokes, "{c}: {r}");
    }
}

#[test]
fn an_uncovered_character_names_the_sources_tried_and_how_to_add_one() {
    let dir = tempfile::tempdir().unwrap();
    // A private-use code point and an extension-B character hanzi-writer-data does not have.
    for (c, code) in [("\u{E000}", "U+E000"), ("𪚥", "U+2A6A5")] {
        let out = dir.path().join("o");
        let o = maobi(&["write", c, "--size", "64", "-o", s(&out)]);
        assert_eq!(o.status.code(), Some(2), "{c}");
        let e = stderr(&o);
        assert!(e.contains(code) && e.contains("is not in the embedded hanzi-writer-data"), "{c}: {e}");
        for how in ["--font FILE", "--image FILE", "--hanzi-data DIR", "npm pack hanzi-writer-data"] {
            assert!(e.contains(how), "{c}: the message names {how}: {e}");
        }
        assert!(!out.exists(), "nothing written for {c}");
    }
}

#[test]
fn hanzi_data_may_be_the_folder_npm_pack_unpacked_into() {
    let dir = tempfile::tempdir().unwrap();
    // `npm pack hanzi-writer-data && tar xzf …` gives npm/package/<char>.json; this one holds 永.
    let npm = dir.path().join("npm");
    std::fs::create_dir_all(npm.join("package")).unwrap();
    let subset =
        std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../trajectory/data/hanzi-subset.jsonl")).unwrap();
    let line = subset.lines().find(|l| l.starts_with("{\"c\":\"永\"")).unwrap();
    std::fs::write(npm.join("package/永.json"), line).unwrap();
    for (name, folder) in [("parent", npm.clone()), ("package", npm.join("package"))] {
        let out = dir.path().join(name);
        ok(&maobi(&["write", "永", "--hanzi-data", s(&folder), "--size", "64", "-o", s(&out)]));
        let r = report(&out);
        assert_eq!(r["source"], "hanzi-data", "{name}: {r}");
        assert_eq!(r["plan"]["strokes_found"], 5, "{name}: {r}");
    }
    // A character the folder lacks: the folders searched, and how to add a source.
    let o = maobi(&["write", "眠", "--hanzi-data", s(&npm), "--size", "64", "-o", s(&dir.path().join("x"))]);
    assert_eq!(o.status.code(), Some(2));
    let e = stderr(&o);
    let package = npm.join("package");
    assert!(e.contains(&format!("the hanzi-writer-data folder {}", package.display())), "{e}");
    assert!(e.contains("--font FILE"), "{e}");
}
