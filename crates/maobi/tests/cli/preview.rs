//! `maobi preview` in a real headless browser (Debian's `chromium`): the page loads without
//! console errors, the animation advances and footprints appear, and a screenshot is taken
//! (`$CARGO_TARGET_TMPDIR/preview.png`). Skipped, saying so, when no chromium is installed.

use crate::common::{maobi, ok, s};
use std::path::{Path, PathBuf};
use std::process::Command;

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/robot").join(name)
}

fn chromium() -> Option<PathBuf> {
    for name in ["chromium", "chromium-browser", "google-chrome", "google-chrome-stable"] {
        if let Ok(o) = Command::new("sh").args(["-c", &format!("command -v {name}")]).output() {
            let p = String::from_utf8_lossy(&o.stdout).trim().to_string();
            if o.status.success() && !p.is_empty() {
                return Some(PathBuf::from(p));
            }
        }
    }
    None
}

/// The `data-*` attributes of `<body>` in a dumped DOM.
fn body_attr(dom: &str, name: &str) -> Option<f64> {
    let body = &dom[dom.find("<body")?..];
    let body = &body[..body.find('>')?];
    let key = format!("data-{name}=\"");
    let rest = &body[body.find(&key)? + key.len()..];
    rest[..rest.find('"')?].parse().ok()
}

#[test]
fn the_page_is_self_contained_and_offline() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("w");
    ok(&maobi(&["write", "十口", "--size", "64", "--sheet", "A5", "--grid", "tian", "--no-marks", "--out", s(&out)]));
    let html = std::fs::read_to_string(out.join("preview.html")).unwrap();
    // No network: no external scripts, styles, images or fetches.
    for needle in ["http://", "https://", "src=", "fetch(", "<link", "import "] {
        assert!(!html.contains(needle), "preview.html contains {needle:?}");
    }
    assert!(html.contains("\"grid\":\"tian\"") && html.contains("\"feet\":["));
    // The command on its own, with the paper, an ink station and another sheet.
    let p = dir.path().join("p.html");
    let said = ok(&maobi(&[
        "preview",
        s(&out.join("track.json")),
        "--sheet",
        "A4",
        "--paper",
        s(&fixture("paper.json")),
        "--robot",
        s(&fixture("robot-ink.json")),
        "-o",
        s(&p),
    ]));
    assert!(said.contains("preview of"), "{said}");
    let page = std::fs::read_to_string(&p).unwrap();
    assert!(page.contains("\"sheet_mm\":[210.0,297.0]") && page.contains("safe (on the given paper.json)"));
    assert!(page.contains("1 ink dip(s)") && page.contains("\"dip_spans\":[["), "the dip is shown");
    // One writing time, from the timing: the one `robot check` reports for the same program.
    let check = ok(&maobi(&[
        "robot",
        "check",
        s(&out.join("track.json")),
        "--paper",
        s(&fixture("paper.json")),
        "--robot",
        s(&fixture("robot-ink.json")),
    ]));
    let after = &check[check.find("writing time ").expect("check reports the writing time") + 13..];
    let writing_s: f64 = after.split_whitespace().next().unwrap().parse().unwrap();
    assert!(writing_s > 1.0, "{check}");
    let shown = page.split(" s of it on the paper (the strokes' timing").next().unwrap();
    let shown_s: f64 = shown.rsplit(", ").next().unwrap().parse().unwrap();
    // The check prints two decimals, the preview one.
    assert!((shown_s - writing_s).abs() <= 0.051, "preview {shown_s} s, check {writing_s} s");
    // Each timed stroke's span on the timeline, as many as `robot check` times.
    let timed = check.lines().filter(|l| l.starts_with("stroke ")).count();
    let data = &page[page.find("\"strokes_s\":").expect("stroke spans") + 12..];
    let spans: Vec<[f64; 2]> = serde_json::from_str(&data[..data.find("]]").unwrap() + 2]).unwrap();
    assert_eq!(spans.len(), timed, "{check}");
    assert!(spans.windows(2).all(|w| w[0][1] <= w[1][0] && w[0][0] < w[0][1]), "{spans:?}");
    // A track the robot check refuses is still previewed, with the refusal as the verdict.
    let small = dir.path().join("small.json");
    std::fs::write(
        &small,
        std::fs::read_to_string(fixture("paper.json"))
            .unwrap()
            .replace("\"size_mm\": [300, 300]", "\"size_mm\": [20, 20]"),
    )
    .unwrap();
    ok(&maobi(&["preview", s(&out.join("track.json")), "--paper", s(&small), "-o", s(&p), "--force"]));
    assert!(std::fs::read_to_string(&p).unwrap().contains("refused (on the given paper.json)"));
    crate::common::fails(&maobi(&["preview", s(&dir.path().join("none.json")), "-o", s(&p)]), "none.json");
}

#[test]
fn the_preview_plays_in_headless_chromium() {
    let Some(browser) = chromium() else {
        eprintln!("skipped: no chromium found (apt-get install chromium); the preview was not tested in a browser");
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("w");
    ok(&maobi(&["write", "十口", "--size", "64", "--sheet", "A5", "--grid", "mi", "--out", s(&out)]));
    let page = out.join("preview.html");
    let url = format!("file://{}#autoplay&speed=4", page.display());
    let run = |extra: &[&str]| {
        Command::new(&browser)
            .args(["--headless", "--no-sandbox", "--disable-gpu", "--no-first-run", "--hide-scrollbars"])
            .arg(format!("--user-data-dir={}", dir.path().join("profile").display()))
            .args(["--enable-logging=stderr", "--v=0", "--virtual-time-budget=3000", "--window-size=1300,900"])
            .args(extra)
            .arg(&url)
            .output()
            .expect("chromium runs")
    };
    let o = run(&["--dump-dom"]);
    let dom = String::from_utf8_lossy(&o.stdout);
    let log = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "chromium failed: {log}");
    assert_eq!(body_attr(&dom, "ready"), Some(1.0), "the script did not finish loading: {log}");
    assert_eq!(body_attr(&dom, "errors"), Some(0.0), "console errors: {log}");
    assert!(!log.contains("Uncaught"), "{log}");
    // 3 s of (virtual) time at 4×: about 12 s of the program played, footprints drawn.
    let t = body_attr(&dom, "t").unwrap();
    let drawn = body_attr(&dom, "drawn").unwrap();
    let feet = body_attr(&dom, "feet").unwrap();
    assert!(t > 1.0, "the animation did not advance: t = {t}");
    assert!(drawn > 0.0 && drawn <= feet && feet > 100.0, "drawn {drawn} of {feet}");
    // Without #autoplay the page opens on the finished sheet: the clock at the end, every
    // footprint drawn, and the verdict's time is the timeline's.
    let o = Command::new(&browser)
        .args(["--headless", "--no-sandbox", "--disable-gpu", "--no-first-run", "--dump-dom"])
        .arg(format!("--user-data-dir={}", dir.path().join("profile").display()))
        .args(["--virtual-time-budget=1000"])
        .arg(format!("file://{}", page.display()))
        .output()
        .expect("chromium runs");
    let still = String::from_utf8_lossy(&o.stdout);
    let duration = body_attr(&still, "duration").unwrap();
    assert_eq!(body_attr(&still, "t"), Some(duration), "not the finished sheet on load");
    assert_eq!(body_attr(&still, "drawn"), body_attr(&still, "feet"));
    assert_eq!(body_attr(&still, "playing"), Some(0.0));
    let html = std::fs::read_to_string(&page).unwrap();
    assert!(html.contains(&format!("{duration:.1} s to write")), "one time in the verdict and the timeline");
    assert!(html.contains("#autoplay") && html.contains("#speed=N"), "the URL options are on the page");
    let shot = Path::new(env!("CARGO_TARGET_TMPDIR")).join("preview.png");
    let _ = std::fs::remove_file(&shot);
    let o = run(&[&format!("--screenshot={}", shot.display())]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let png = std::fs::read(&shot).unwrap();
    assert!(png.starts_with(b"\x89PNG") && png.len() > 10_000, "screenshot of {} bytes", png.len());
    eprintln!("screenshot: {}", shot.display());
}

/// A hostile `char` field cannot add markup or script to the page: the title is escaped, the
/// inline JSON holds no `<`, and neither placeholder is filled from the other's text.
#[test]
fn a_hostile_char_field_stays_text_in_the_page() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("w");
    ok(&maobi(&["write", "十", "--size", "64", "--out", s(&out)]));
    let track = out.join("track.json");
    let mut t: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&track).unwrap()).unwrap();
    let hostile = "十</script><script>document.title='pwned'</script><!--<script>__DATA__ __TITLE__ '\"&";
    t["char"] = serde_json::Value::String(hostile.into());
    std::fs::write(&track, serde_json::to_string(&t).unwrap()).unwrap();
    let p = dir.path().join("p.html");
    ok(&maobi(&["preview", s(&track), "-o", s(&p)]));
    let html = std::fs::read_to_string(&p).unwrap();
    let template = include_str!("../../../figures/src/preview.html");
    assert_eq!(html.matches("<script").count(), template.matches("<script").count());
    assert_eq!(html.matches("</script").count(), template.matches("</script").count());
    assert!(!html.contains("<!--"), "a comment opener reached the page");
    // The data element still parses, and its title is the text as given.
    let start = html.find("id=\"data\">").unwrap() + "id=\"data\">".len();
    let end = start + html[start..].find("</script>").unwrap();
    let data: serde_json::Value = serde_json::from_str(&html[start..end]).unwrap();
    assert_eq!(data["title"], hostile);
    // The <title> holds the escaped text once; the placeholders were filled once each.
    let title = &html[html.find("<title>").unwrap()..html.find("</title>").unwrap()];
    assert!(title.contains("十&lt;/script&gt;") && title.contains("__DATA__ __TITLE__ &#39;&quot;&amp;"), "{title}");
}
