//! A sheet folder and an observation folder read back (issue 43): the input is split at 0xFF
//! bytes into a sheet's track.json, an observation's summary.json and one observed.png,
//! written to files and read as `maobi observe` and `write --observed` read them. No panic;
//! what is accepted holds what its readers index (stroke ranges inside the strokes,
//! `stroke_chars` naming the characters, at most six marks, folder names that are one path
//! component) and an observation accepted against the sheet has its characters.
#![no_main]

use libfuzzer_sys::fuzz_target;
use std::path::Component;

fuzz_target!(|data: &[u8]| {
    let mut parts = data.splitn(3, |&b| b == 0xFF);
    let (track, summary, png) = (parts.next().unwrap_or(b""), parts.next().unwrap_or(b""), parts.next().unwrap_or(b""));
    let dir = std::env::temp_dir().join(format!("maobi-fuzz-sheet-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let (tp, sp, pp) = (dir.join("track.json"), dir.join("summary.json"), dir.join("observed.png"));
    std::fs::write(&tp, track).unwrap();
    std::fs::write(&sp, summary).unwrap();
    std::fs::write(&pp, png).unwrap();
    let sheet = pipeline::SheetTrack::load(&tp);
    if let Ok((t, bytes)) = &sheet {
        assert!(!t.chars.is_empty() && t.chars.len() <= pipeline::MAX_SHEET_CHARS);
        assert!(t.marks.len() <= 6 && t.mark_strokes == 2 * t.marks.len());
        assert_eq!(t.stroke_chars.len(), t.strokes.len());
        for (i, c) in t.chars.iter().enumerate() {
            let strokes = &t.strokes[c.strokes[0]..c.strokes[1]];
            assert!(strokes.iter().enumerate().all(|(k, _)| t.stroke_chars[c.strokes[0] + k] == i));
            let name = pipeline::char_folder(i, &c.char);
            let mut comps = std::path::Path::new(&name).components();
            assert!(matches!((comps.next(), comps.next()), (Some(Component::Normal(_)), None)), "{name}");
            assert!(c.char_box_mm.iter().all(|v| v.is_finite()) && c.char_box_mm[2] >= 1.0);
        }
        assert!(pipeline::fingerprint(bytes).starts_with("fnv1a64:"));
    }
    if let Ok(o) = pipeline::Observation::load(&sp) {
        assert!(o.sheet.path.is_absolute());
        assert!(!o.chars.is_empty() && o.chars.len() <= pipeline::MAX_SHEET_CHARS);
        for (i, c) in o.chars.iter().enumerate() {
            assert_eq!(c.folder, pipeline::char_folder(i, &c.char));
            assert!((pipeline::OBSERVED_PX[0]..=pipeline::OBSERVED_PX[1]).contains(&c.size_px));
        }
        if let Ok((t, bytes)) = &sheet {
            if o.check_sheet(&sp, t, &tp, bytes).is_ok() {
                assert_eq!(o.chars.len(), t.chars.len());
            }
        }
    }
    // The observed image: header first, decoded only within the limits.
    if bezier_raster::image_header(&pp).is_ok() {
        let _ = bezier_raster::Coverage::load(&pp);
    }
});
