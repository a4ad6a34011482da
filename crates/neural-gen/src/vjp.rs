//! Batched footprint images and their vector–Jacobian products with respect to the press,
//! without candle's autograd.
//!
//! Track refinement needs, for every footprint of a character (thousands), the image and then,
//! once the loss of all images together is known, `∂L/∂(h, α, β)` from `∂L/∂image`. That is a
//! gradient with respect to the network's *input* only, so the weight gradients candle's
//! autograd computes on every backward pass (a third of the work) are not needed, and neither is
//! the graph. [`InputVjp`] copies the generator's weights out of candle once and runs the same
//! network on plain buffers with its own kernels (`net`, `kernels`: packed matrix products for the
//! fully connected layers, on the whole batch; register-tiled 3×3 correlations for the
//! convolution stages, image by image in parallel, with bias, ReLU, pixel shuffle and sigmoid
//! fused into the pass that writes the next layer's padded input): [`InputVjp::forward`] keeps
//! what the backward pass needs (the ReLU masks, one byte per activation, and the images, a
//! [`Tape`]), [`InputVjp::vjp`] runs the backward pass to the input. One forward and one
//! backward per batch, and the forward's images can be used (to compute the upstream gradient)
//! before the backward runs.
//!
//! Every image is computed independently of the others in its batch, every sum in a fixed
//! order of fused multiply–adds, so the results do not depend on the batch size, the thread
//! count or the vector width. Training (`direct`) runs on the same network.
//! Tested against candle's autograd ([`crate::Generator::image_and_vjp`]) and against finite
//! differences.

use brush_model::Press;

use crate::NeuralGenError;
use crate::config::GeneratorConfig;
use crate::net::{Net, NetSpec, Tape};

/// The generator's network on plain buffers, for batched images and input VJPs (see the
/// module doc): [`crate::Generator::kernels`] builds one (cloning it gives a copy to own).
#[derive(Clone)]
pub struct InputVjp {
    net: Net,
    config: GeneratorConfig,
    /// Normalised input per unit of h (per mm), α and β (per rad).
    slopes: [f64; 3],
}

impl InputVjp {
    /// The network of `config` with the weights `get(name)` returns (`fc0.weight`, …, as
    /// candle names and lays them out).
    ///
    /// # Errors
    /// What `get` returns; [`NeuralGenError::Shape`] for a tensor of the wrong size.
    pub(crate) fn new(
        config: &GeneratorConfig,
        get: impl Fn(&str) -> Result<Vec<f32>, NeuralGenError>,
    ) -> Result<Self, NeuralGenError> {
        Ok(Self {
            net: Net::new(&NetSpec::of_arch(&config.arch), get)?,
            config: config.clone(),
            slopes: config.normalise_slopes(),
        })
    }

    /// Side of the images, px.
    pub fn size(&self) -> usize {
        self.net.size
    }

    /// The forward pass for a batch of presses (β as the generator takes it: inside its
    /// calibrated range), keeping what [`InputVjp::vjp`] needs. The fully connected layers
    /// run on the whole batch, the convolutions image by image in parallel.
    pub fn forward(&self, presses: &[Press]) -> Tape {
        let x: Vec<f32> = presses.iter().flat_map(|p| self.config.normalise(p)).collect();
        self.net.forward_taped(&x)
    }

    /// Images for a batch of normalised inputs `x` (`[batch, 3]`, as
    /// [`crate::GeneratorConfig::normalise`] makes them): `batch × size²` values in [0, 1],
    /// image after image. Inference only: the same numbers as [`InputVjp::forward`]'s images,
    /// without keeping a tape. The fully connected layers run on the whole batch, the
    /// convolutions image by image in parallel; the bits do not depend on the batch or the
    /// thread count.
    ///
    /// # Panics
    /// When `x.len()` is not a multiple of 3.
    pub(crate) fn images_normalised(&self, x: &[f32]) -> Vec<f32> {
        self.net.images(x)
    }

    /// As [`InputVjp::images_normalised`], each image in a vector of its own (`size²` values),
    /// written where the image is computed (no copy out of a batch buffer).
    ///
    /// # Panics
    /// When `x.len()` is not a multiple of 3.
    pub(crate) fn images_normalised_each(&self, x: &[f32]) -> Vec<Vec<f32>> {
        self.net.images_each(x)
    }

    /// The Jacobian of each image with respect to its press by forward-mode differentiation
    /// (three tangents through the network, the forward pass's ReLU masks reused):
    /// `len() × 3 × size²` values, per image `∂image/∂h` (per mm), `∂image/∂α`, `∂image/∂β`
    /// (per rad). `Σ upstream · ∂image/∂p` equals [`InputVjp::vjp`]'s, and with the Jacobian
    /// a press shared by many uses gives each use its own product without another pass.
    pub fn jacobian(&self, tape: &Tape) -> Vec<f32> {
        self.jacobian_of(tape, [true; 3])
    }

    /// As [`InputVjp::jacobian`] for the inputs marked in `which` (h, α, β) only; the columns
    /// of the others are left zero (one tangent pass per marked input).
    pub fn jacobian_of(&self, tape: &Tape, which: [bool; 3]) -> Vec<f32> {
        // The unit step of each input in normalised units.
        let k = self.slopes;
        self.net.jacobian(tape, which, [k[0] as f32, k[1] as f32, k[2] as f32])
    }

    /// The gradient of `Σ upstream · image` with respect to each press `(h [per mm], α [per
    /// rad], β [per rad])`, `upstream` holding `size²` values per image of the tape.
    ///
    /// # Errors
    /// [`NeuralGenError::Shape`] when `upstream` does not hold `size²` values per image.
    pub fn vjp(&self, tape: &Tape, upstream: &[f32]) -> Result<Vec<[f64; 3]>, NeuralGenError> {
        let (b, s) = (tape.len(), self.size());
        if upstream.len() != b * s * s {
            return Err(NeuralGenError::Shape(format!(
                "upstream gradient has {} values, expected {} ({} images of {}²)",
                upstream.len(),
                b * s * s,
                b,
                s
            )));
        }
        let g = self.net.input_gradient(tape, upstream);
        let k = self.slopes;
        Ok(g.chunks_exact(3).map(|v| [v[0] as f64 * k[0], v[1] as f64 * k[1], v[2] as f64 * k[2]]).collect())
    }
}

#[cfg(test)]
mod tests {
    /// Inference (no masks kept, the images in a batch buffer or one vector each) gives the
    /// same bits as the forward pass that keeps its tape, for the shipped architecture (its
    /// larger stages run in several bands of rows) and an odd one.
    #[test]
    fn inference_equals_the_taped_forward_pass() {
        use crate::{Arch, Generator, GeneratorConfig};
        use brush_model::{BrushProfile, Press};
        let odd =
            Arch { hidden: vec![24, 40], seed_channels: 12, seed_side: 3, stages: vec![(12, 20), (5, 12), (3, 4)] };
        for arch in [Arch::default_128(), odd] {
            let g = Generator::new(GeneratorConfig::new(BrushProfile::builtin("pen1").unwrap(), arch), 2).unwrap();
            let ps: Vec<Press> =
                (0..5).map(|i| Press::from_degrees(11.0 + 2.0 * i as f64, 3.0 * i as f64, 1.0 * i as f64)).collect();
            let x: Vec<f32> = ps.iter().flat_map(|p| g.config.normalise(p)).collect();
            let net = g.kernels().unwrap();
            let taped = net.forward(&ps);
            let flat = net.images_normalised(&x);
            assert_eq!(taped.images(), &flat[..]);
            let each: Vec<f32> = net.images_normalised_each(&x).concat();
            assert_eq!(each, flat);
            assert!(flat.iter().any(|&v| v > 0.01 && v < 0.99), "a flat image tests little");
        }
    }
}
