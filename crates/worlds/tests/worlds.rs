//! The worlds behave as they say: one that agrees with the model leaves the model's ink; one
//! whose hairs need a press is not turned by a glide lighter than that.

use bezier_raster::{Stamp, sweep_stamps};
use brush_model::{BrushProfile, Extrapolation, HairMotion, TrackPoint};
use pipeline::{WriteOptions, prepare, write_char};
use trajectory::CharBox;
use worlds::{World, ink};

fn pen1_with(contact_h_mm: f64) -> BrushProfile {
    let pen1 = BrushProfile::builtin("pen1").unwrap();
    BrushProfile { hairs: HairMotion { contact_h_mm, ..pen1.hairs }, ..pen1 }
}

fn pt(x_mm: f64, y_mm: f64, h_mm: f64) -> TrackPoint {
    TrackPoint { x_mm, y_mm, h_mm, alpha_rad: 0.0, beta_rad: 0.0 }
}

/// 永 written by `profile` and executed as sent: the executed brush states and the box.
fn executed(ch: char, profile: &BrushProfile) -> (Vec<TrackPoint>, CharBox) {
    let p = prepare(trajectory::embedded_glyph(ch).unwrap(), None).unwrap();
    let b = CharBox { x0_mm: 0.0, y0_mm: 0.0, size_mm: trajectory::auto_char_mm(&p.paths, profile, 0.0) };
    let opts = WriteOptions { size: 64, free_widths: false, ..WriteOptions::default() };
    let r = write_char(&p, profile, b, &opts).unwrap();
    (r.executed_states.unwrap(), b)
}

fn assert_same(world: &[Stamp], model: &[Stamp], what: &str) {
    assert_eq!(world.len(), model.len(), "{what}: stamp count");
    for (w, m) in world.iter().zip(model) {
        let close = |a: f64, b: f64| (a - b).abs() < 1e-9;
        assert!(
            close(w.anchor.x_mm, m.anchor.x_mm)
                && close(w.anchor.y_mm, m.anchor.y_mm)
                && close(brush_model::wrap_angle_rad(w.beta_rad - m.beta_rad), 0.0)
                && close(w.footprint.lt_mm, m.footprint.lt_mm)
                && close(w.footprint.lr_mm, m.footprint.lr_mm),
            "{what}: {w:?} vs {m:?}"
        );
    }
}

/// With no lag, no spread, the model's brush and the profile's hairs, a world leaves the
/// forward model's footprints along an executed path, for hairs that follow any touch (contact
/// depth 0: the zero-threshold world) and for the nominal hairs (1 mm).
#[test]
fn a_world_that_agrees_with_the_model_leaves_the_models_ink() {
    for contact in [0.0, 1.0] {
        let profile = pen1_with(contact);
        let (states, b) = executed('永', &profile);
        let world = World::of_profile(&profile);
        assert_eq!(world, World { contact_h_mm: contact, ..World::MODEL });
        let w = world.stamps(&states, &profile);
        let m = sweep_stamps(&states, &profile, Extrapolation::Refuse);
        assert!(m.len() > 1000, "{} footprints", m.len());
        assert_same(&w, &m, &format!("contact {contact}"));
        let (a, c) = (ink(&w, b.x0_mm, b.y0_mm, b.size_mm, 128), ink(&m, b.x0_mm, b.y0_mm, b.size_mm, 128));
        assert_eq!(a.data(), c.data());
    }
}

/// A reverse entry back to x = 10, a glide to x = 25, a press again and on to 60: hairs that
/// need 0.05 mm are not turned by a glide at 0.01 mm (the first footprints after the press point
/// forward, β = 0, past the stroke's end for a short stroke), and are by one at 0.5 mm, as
/// hairs that follow any touch are by either; lighter than the contact depth nothing inks.
#[test]
fn a_world_whose_hairs_need_a_press_is_not_turned_by_a_light_glide() {
    let pen1 = BrushProfile::builtin("pen1").unwrap();
    let path = |glide: f64| {
        [
            pt(30.0, 20.0, 13.0),
            pt(10.0, 20.0, 13.0),
            pt(10.0, 20.0, glide),
            pt(25.0, 20.0, glide),
            pt(25.0, 20.0, 13.0),
            pt(60.0, 20.0, 13.0),
        ]
    };
    // The footprints written after the glide (the entry's run from x = 30 back to 10 first).
    let after = |s: Vec<Stamp>| -> Vec<Stamp> {
        let entry_end = s.iter().position(|s| s.anchor.x_mm <= 10.0 + 1e-9).unwrap();
        s[entry_end..].iter().copied().filter(|s| s.anchor.x_mm > 25.0 + 1e-9).collect()
    };
    let first_after = |w: &World, glide: f64| -> f64 { after(w.stamps(&path(glide), &pen1))[0].beta_rad.cos() };
    let touch = World::parse("pressure:0").unwrap();
    let press = World::parse("pressure:0.05").unwrap();
    assert!(first_after(&touch, 0.01) < -0.99, "any touch turns the hairs");
    assert!(first_after(&press, 0.01) > 0.99, "a 0.01 mm glide leaves them pointing forward");
    assert!(first_after(&press, 0.5) < -0.99, "a 0.5 mm glide turns them");
    // The forward footprints are there until pressed motion has pulled the hairs round.
    let s = after(press.stamps(&path(0.01), &pen1));
    let forward = s.iter().filter(|s| s.beta_rad.cos() > 0.99).count();
    assert!(forward > 30, "{forward} forward footprints");
    // A path lighter than the contact depth throughout leaves nothing and no history.
    let light = [pt(0.0, 0.0, 0.04), pt(20.0, 0.0, 0.04)];
    assert!(press.stamps(&light, &pen1).is_empty());
}

/// Light presses (past the contact depth, lighter than the calibrated range) ink only in a
/// world that says so; the mismatched brush leaves more ink than the model's.
#[test]
fn light_ink_and_the_mismatched_brush() {
    let pen1 = BrushProfile::builtin("pen1").unwrap();
    let glide = [pt(10.0, 20.0, 5.0), pt(40.0, 20.0, 5.0)];
    assert!(World::parse("pressure:1").unwrap().stamps(&glide, &pen1).is_empty());
    let light = World::parse("pressure:1,light").unwrap().stamps(&glide, &pen1);
    assert!(light.len() > 250, "{}", light.len());
    // pen1 pressed 5 mm, extrapolated: a belly 2 × 1.6·6/48·5 = 2 mm wide.
    assert!(light.iter().all(|s| (s.footprint.lr_mm - 1.0).abs() < 1e-9), "{:?}", light[0]);
    let bar = [pt(10.0, 20.0, 14.0), pt(60.0, 20.0, 14.0)];
    let model = ink(&World::MODEL.stamps(&bar, &pen1), 0.0, 0.0, 80.0, 160);
    let wide = ink(&World::MISMATCH.stamps(&bar, &pen1), 0.0, 0.0, 80.0, 160);
    assert!(wide.ink() > 1.2 * model.ink(), "{} vs {}", wide.ink(), model.ink());
}
