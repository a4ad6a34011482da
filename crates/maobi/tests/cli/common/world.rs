//! A world that is not the model, and a camera, for the closed-loop tests: ink made by a brush
//! that writes differently from `brush_model::ForwardModel` (wider, longer, hairs lagging and
//! trailing differently and turning only under a press, ink spreading: the `worlds` crate),
//! photographed by a simulated camera (a pose with tilt, lens blur, uneven light, noise, JPEG).
//! The world's and the camera's constants live in test code only (docs/closed-loop.md): maobi's
//! library code must not know them.

#![allow(dead_code)]

use std::path::Path;

use bezier_raster::{ModelKind, Stamp, render_stamps};
use brush_model::{BrushProfile, PointMm, Stroke};
pub use worlds::World as WorldBrush;
pub use worlds::{MISMATCH_LAG_MM as WORLD_LAG_MM, MISMATCH_TRAIL_REACH as WORLD_TRAIL_REACH};

use super::{maobi, ok, s};

// ---- The world: how its brush writes (differs from the profile and the forward model). ----

/// The depth from which the test world's hairs follow motion, mm: the top of the range issue 44
/// asks the worlds to cover (the planner's glides must turn them without the loop's help).
pub const WORLD_CONTACT_H_MM: f64 = 1.0;

/// The test world's brush: the mismatched brush of `worlds` (belly ×1.18, lengths ×1.12, root
/// lag 0.4 mm, tip 0.3 footprint lengths back, spread 0.3 mm) whose hairs need
/// [`WORLD_CONTACT_H_MM`] of press to turn.
pub const WORLD: WorldBrush = WorldBrush { contact_h_mm: WORLD_CONTACT_H_MM, ..WorldBrush::MISMATCH };

/// The world's paper raster, px per mm.
pub const WORLD_PX_PER_MM: f64 = 8.0;

/// A world whose brush is the one the profile describes, written the forward model's way with
/// the nominal hairs (tip half a footprint back, following from 1 mm of press; no lag, no
/// spread): the "world equals the model" baseline.
pub const MODEL_WORLD: WorldBrush = WorldBrush { contact_h_mm: brush_model::CONTACT_H_MM, ..WorldBrush::MODEL };

/// The world's footprints along `strokes` (paper mm).
pub fn world_stamps(strokes: &[Stroke], profile: &BrushProfile) -> Vec<Stamp> {
    WORLD.track_stamps(strokes, profile)
}

/// The footprints of a world with brush `w` along `strokes` (paper mm).
pub fn world_stamps_with(strokes: &[Stroke], profile: &BrushProfile, w: &WorldBrush) -> Vec<Stamp> {
    w.track_stamps(strokes, profile)
}

/// The world's ink in a frame: `size²` px over the box `[x0, y0, side]` mm.
pub fn world_ink(stamps: &[Stamp], b: [f64; 3], size: u32) -> bezier_raster::Coverage {
    worlds::ink(stamps, b[0], b[1], b[2], size)
}

// ---- The camera. ----

/// A deterministic random stream (SplitMix64).
pub struct Rng(pub u64);

impl Rng {
    pub fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }
    pub fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.next()
    }
    pub fn gauss(&mut self) -> f64 {
        let (u, v) = (self.next().max(1e-12), self.next());
        (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()
    }
}

/// How the camera sees the sheet.
#[derive(Clone, Copy, Debug)]
pub struct Camera {
    /// Tilt about the paper's x and y axes, degrees.
    pub tilt_deg: [f64; 2],
    /// Turn about the optical axis, degrees.
    pub yaw_deg: f64,
    /// Lens blur, Gaussian σ in photo px.
    pub blur_px: f64,
    /// Sensor noise, σ in units of full scale.
    pub noise: f64,
    /// JPEG quality.
    pub quality: u8,
}

pub const PHOTO_W: usize = 1700;
pub const PHOTO_H: usize = 2300;
pub const FOCAL_PX: f64 = 2000.0;

pub type M3 = [[f64; 3]; 3];

pub fn mul(a: &M3, b: &M3) -> M3 {
    std::array::from_fn(|r| std::array::from_fn(|c| (0..3).map(|k| a[r][k] * b[k][c]).sum()))
}

pub fn inv(m: &M3) -> M3 {
    let c = |r: usize, k: usize| {
        let (r1, r2, c1, c2) = ((r + 1) % 3, (r + 2) % 3, (k + 1) % 3, (k + 2) % 3);
        m[r1][c1] * m[r2][c2] - m[r1][c2] * m[r2][c1]
    };
    let det: f64 = (0..3).map(|k| m[0][k] * c(0, k)).sum();
    std::array::from_fn(|r| std::array::from_fn(|k| c(k, r) / det))
}

pub fn apply(m: &M3, p: [f64; 2]) -> [f64; 2] {
    let w = m[2][0] * p[0] + m[2][1] * p[1] + m[2][2];
    [(m[0][0] * p[0] + m[0][1] * p[1] + m[0][2]) / w, (m[1][0] * p[0] + m[1][1] * p[1] + m[1][2]) / w]
}

/// Paper mm → photo px for a camera `dist_mm` above the sheet's centre.
pub fn camera_h(cam: &Camera, sheet_mm: [f64; 2], dist_mm: f64) -> M3 {
    camera_h_sized(cam, sheet_mm, dist_mm, [PHOTO_W, PHOTO_H], FOCAL_PX)
}

/// As [`camera_h`] for a sensor of `size` px with focal length `focal_px`.
pub fn camera_h_sized(cam: &Camera, sheet_mm: [f64; 2], dist_mm: f64, size: [usize; 2], focal_px: f64) -> M3 {
    let (tx, ty, yaw) = (cam.tilt_deg[0].to_radians(), cam.tilt_deg[1].to_radians(), cam.yaw_deg.to_radians());
    let rx = [[1.0, 0.0, 0.0], [0.0, tx.cos(), -tx.sin()], [0.0, tx.sin(), tx.cos()]];
    let ry = [[ty.cos(), 0.0, ty.sin()], [0.0, 1.0, 0.0], [-ty.sin(), 0.0, ty.cos()]];
    let rz = [[yaw.cos(), -yaw.sin(), 0.0], [yaw.sin(), yaw.cos(), 0.0], [0.0, 0.0, 1.0]];
    let r = mul(&rz, &mul(&rx, &ry));
    let k = [[focal_px, 0.0, size[0] as f64 / 2.0], [0.0, focal_px, size[1] as f64 / 2.0], [0.0, 0.0, 1.0]];
    let rt = [[r[0][0], r[0][1], 0.0], [r[1][0], r[1][1], 0.0], [r[2][0], r[2][1], dist_mm]];
    let centre = [[1.0, 0.0, -sheet_mm[0] / 2.0], [0.0, 1.0, -sheet_mm[1] / 2.0], [0.0, 0.0, 1.0]];
    mul(&k, &mul(&rt, &centre))
}

pub fn gaussian_blur(img: &mut [f32], w: usize, h: usize, sigma: f64) {
    let r = (3.0 * sigma).ceil() as isize;
    let k: Vec<f32> = (-r..=r).map(|i| (-(i * i) as f64 / (2.0 * sigma * sigma)).exp() as f32).collect();
    let sum: f32 = k.iter().sum();
    let k: Vec<f32> = k.iter().map(|v| v / sum).collect();
    let mut tmp = vec![0f32; img.len()];
    for y in 0..h {
        for x in 0..w {
            tmp[y * w + x] = (-r..=r)
                .map(|i| k[(i + r) as usize] * img[y * w + (x as isize + i).clamp(0, w as isize - 1) as usize])
                .sum();
        }
    }
    for y in 0..h {
        for x in 0..w {
            img[y * w + x] = (-r..=r)
                .map(|i| k[(i + r) as usize] * tmp[(y as isize + i).clamp(0, h as isize - 1) as usize * w + x])
                .sum();
        }
    }
}

/// The world's sheet photographed: a JPEG, and the true paper mm → photo px map.
pub fn photograph(stamps: &[Stamp], sheet_mm: [f64; 2], cam: &Camera, seed: u64) -> (Vec<u8>, M3) {
    photograph_sized(stamps, sheet_mm, cam, seed, [PHOTO_W, PHOTO_H], FOCAL_PX)
}

/// As [`photograph`] with a sensor of `size` px and focal length `focal_px` (a smaller photo
/// for the tests that take many).
pub fn photograph_sized(
    stamps: &[Stamp],
    sheet_mm: [f64; 2],
    cam: &Camera,
    seed: u64,
    size: [usize; 2],
    focal_px: f64,
) -> (Vec<u8>, M3) {
    let mut rng = Rng(seed);
    // The paper: reflectance with a faint texture, ink nearly black.
    let (pw, ph) = ((sheet_mm[0] * WORLD_PX_PER_MM) as u32, (sheet_mm[1] * WORLD_PX_PER_MM) as u32);
    let ink = render_stamps(stamps, ModelKind::Bsm.model(), PointMm::new(0.0, 0.0), WORLD_PX_PER_MM, pw, ph);
    let refl: Vec<f32> = ink.data().iter().map(|c| (0.9 + 0.02 * rng.gauss() as f32) * (1.0 - 0.88 * c)).collect();
    // Far enough that the whole sheet is in view.
    let mut dist = 300.0;
    let h = loop {
        let h = camera_h_sized(cam, sheet_mm, dist, size, focal_px);
        let inside =
            [[0.0, 0.0], [sheet_mm[0], 0.0], [sheet_mm[0], sheet_mm[1]], [0.0, sheet_mm[1]]].iter().all(|&p| {
                let q = apply(&h, p);
                q[0] > 60.0 && q[1] > 60.0 && q[0] < size[0] as f64 - 60.0 && q[1] < size[1] as f64 - 60.0
            });
        if inside {
            break h;
        }
        dist *= 1.05;
    };
    let hi = inv(&h);
    let (w, hh) = (size[0], size[1]);
    let mut lum = vec![0f32; w * hh];
    for v in 0..hh {
        for u in 0..w {
            let p = apply(&hi, [u as f64 + 0.5, v as f64 + 0.5]);
            let (x, y) = (p[0] * WORLD_PX_PER_MM - 0.5, p[1] * WORLD_PX_PER_MM - 0.5);
            let r = if x >= 0.0 && y >= 0.0 && x < pw as f64 - 1.0 && y < ph as f64 - 1.0 {
                let (x0, y0) = (x as usize, y as usize);
                let (tx, ty) = ((x - x0 as f64) as f32, (y - y0 as f64) as f32);
                let i = y0 * pw as usize + x0;
                let a = refl[i] * (1.0 - tx) + refl[i + 1] * tx;
                let b = refl[i + pw as usize] * (1.0 - tx) + refl[i + pw as usize + 1] * tx;
                a * (1.0 - ty) + b * ty
            } else {
                // A dark wooden table.
                0.28 + 0.03 * ((u / 23 + v / 37) % 3) as f32
            };
            // Light from one side, falling off towards the far corner, and a vignette.
            let (fu, fv) = (u as f32 / w as f32, v as f32 / hh as f32);
            let rr = (fu - 0.5).powi(2) + (fv - 0.5).powi(2);
            let light = (1.0 - 0.35 * fu) * (1.0 - 0.15 * fv) * (1.0 - 0.3 * rr);
            lum[v * w + u] = r * light;
        }
    }
    gaussian_blur(&mut lum, w, hh, cam.blur_px);
    let mut rgb = Vec::with_capacity(w * hh * 3);
    for l in &lum {
        let l = l + (cam.noise * rng.gauss()) as f32;
        for tint in [1.0f32, 0.96, 0.88] {
            rgb.push(((l * tint).clamp(0.0, 1.0) * 255.0).round() as u8);
        }
    }
    let mut jpeg = Vec::new();
    image::codecs::jpeg::JpegEncoder::new_with_quality(&mut jpeg, cam.quality)
        .encode(&rgb, w as u32, hh as u32, image::ExtendedColorType::Rgb8)
        .unwrap();
    (jpeg, h)
}

pub fn json(p: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(p).unwrap()).unwrap()
}

/// Writes `text` on an A4 sheet at 256 px per character; returns the folder.
pub fn write_sheet(dir: &Path, text: &str) -> std::path::PathBuf {
    let out = dir.join(format!("sheet-{text}"));
    ok(&maobi(&["write", text, "--sheet", "A4", "--size", "256", "-o", s(&out)]));
    out
}

pub fn random_camera(rng: &mut Rng, yaw_deg: f64) -> Camera {
    Camera {
        // 12–15° of tilt in a random direction.
        tilt_deg: {
            let (t, phi) = (rng.uniform(12.0, 15.0), rng.uniform(0.0, std::f64::consts::TAU));
            [t * phi.cos(), t * phi.sin()]
        },
        yaw_deg: yaw_deg + rng.uniform(-8.0, 8.0),
        blur_px: 1.2,
        noise: 0.015,
        quality: 70,
    }
}
