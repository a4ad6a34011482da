//! Labelled pictures of the measuring commands' results.

use std::sync::Once;

use anyhow::{Result, anyhow};
use plotters::prelude::*;

/// DejaVu Sans, the subset the `maobi` binary embeds (ASCII, °, ², α, β; Bitstream Vera licence
/// beside it).
static FONT: &[u8] = include_bytes!("../../crates/maobi/data/DejaVuSans-subset.ttf");

fn register_font() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        let _ = plotters::style::register_font("sans-serif", FontStyle::Normal, FONT);
    });
}

/// The panels left to right with a 4 px white gap, each with its label above it, as a PNG.
///
/// # Errors
/// When drawing or encoding fails.
pub fn labelled_row(panels: &[(String, image::RgbImage)]) -> Result<Vec<u8>> {
    register_font();
    let gap = 4u32;
    let img_h = panels.iter().map(|(_, p)| p.height()).max().unwrap_or(0);
    let px = panels.iter().map(|(_, p)| (p.width() / 16).clamp(9, 28)).min().unwrap_or(9);
    let strip = px + 8;
    let w = panels.iter().map(|(_, p)| p.width()).sum::<u32>() + gap * panels.len().saturating_sub(1) as u32;
    let h = strip + img_h;
    let mut buf = vec![255u8; (w * h * 3) as usize];
    let mut x0 = 0u32;
    for (_, p) in panels {
        for (x, y, px) in p.enumerate_pixels() {
            let o = (((strip + y) * w + x0 + x) * 3) as usize;
            buf[o..o + 3].copy_from_slice(&px.0);
        }
        x0 += p.width() + gap;
    }
    {
        let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
        let mut x0 = 0i32;
        for (label, p) in panels {
            let style = ("sans-serif", px).into_font().color(&BLACK);
            root.draw(&Text::new(label.as_str(), (x0 + 4, 3), style)).map_err(|e| anyhow!("{e}"))?;
            x0 += (p.width() + gap) as i32;
        }
        root.present().map_err(|e| anyhow!("{e}"))?;
    }
    let img = image::RgbImage::from_raw(w, h, buf).ok_or_else(|| anyhow!("picture buffer has the wrong size"))?;
    let mut out = Vec::new();
    img.write_to(&mut std::io::Cursor::new(&mut out), image::ImageFormat::Png)?;
    Ok(out)
}
