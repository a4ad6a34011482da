//! Renders a pen1 footprint with every stroke model side by side into `out/models.png`: five
//! unlabelled 128 px cells, left to right bsm, circle, ellipse, line, qbc (the scale is printed).
//! `maobi models --plot FILE` draws the same comparison with named panels and axes in mm.
//!
//! `cargo run -p bezier-raster --example render`

use bezier_raster::{Compositor, ModelKind, Stamp, StrokeCanvas};
use brush_model::{BrushProfile, Extrapolation, PointMm, Press};

fn main() {
    let pen1 = BrushProfile::builtin("pen1").expect("built-in");
    let press = Press::from_degrees(18.0, 8.0, 0.0);
    let fp = pen1.predict(&press, Extrapolation::Refuse).expect("in range");
    let canvas = StrokeCanvas::for_profile(&pen1, 128);
    let cell_mm = canvas.size_mm();
    let mut sheet = Compositor::new(128 * 5, 128, canvas.px_per_mm);
    let mut before = 0.0;
    for (i, m) in ModelKind::ALL.iter().enumerate() {
        let a = canvas.anchor_mm(&fp, press.beta_rad);
        let stamp = Stamp {
            footprint: fp,
            anchor: PointMm::new(a.x_mm + i as f64 * cell_mm, a.y_mm),
            beta_rad: press.beta_rad,
        };
        sheet.stamp(m.model(), &stamp);
        let ink = sheet.image().ink();
        println!("{:<8} ink {:.1} px", m.name(), ink - before);
        before = ink;
    }
    std::fs::create_dir_all("out").expect("out/");
    std::fs::write("out/models.png", sheet.image().encode_png().expect("encodes")).expect("writes");
    println!(
        "wrote out/models.png: cells of {cell_mm:.1} mm ({:.2} px/mm), left to right bsm, circle, ellipse, line, qbc",
        canvas.px_per_mm
    );
}
