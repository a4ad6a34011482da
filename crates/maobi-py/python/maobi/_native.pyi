"""Type stubs of maobi's native module (``maobi._native``), re-exported by ``maobi``.

Units: millimetres (``_mm``) and radians (``_rad``); images ``(H, W)`` float32, ink = 1."""

import os
from typing import Any, Dict, List, Literal, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

__version__: str

PathLike = Union[str, "os.PathLike[str]"]
ArrayLike = npt.ArrayLike
FloatImage = npt.NDArray[np.float32]
BoxMm = Union[float, Tuple[float, float, float]]
BrushArg = Union[str, "Brush", PathLike, None]

class MaobiError(Exception):
    """What maobi refuses or cannot do (a profile that does not validate, a program that fails
    the safety check, an unreadable file); the message names the argument, file or field."""

class Brush:
    """A brush profile: the brush (bundle length and radius, mm), its calibrated press ranges
    and the linear model from a press ``(h_mm, alpha_rad, beta_rad)`` to the footprint's
    lengths ``(lt_mm, lh_mm, lr_mm)`` (tip length, root length, belly half-width, mm)."""

    @staticmethod
    def builtin(name: str) -> Brush:
        """A built-in brush: ``pen1``, ``pen2`` or a scaled pen1 (``pen1-s84`` … ``pen1-s25``).
        Raises ``ValueError`` for an unknown name."""
    @staticmethod
    def builtins() -> List[str]:
        """The names of the built-in brushes."""
    @staticmethod
    def load(path: PathLike) -> Brush:
        """A profile JSON file (as ``maobi calibrate -o`` writes it), validated. Raises
        ``FileNotFoundError``, or ``MaobiError`` naming the field for an invalid profile."""
    @staticmethod
    def from_json(text: str) -> Brush:
        """A profile from its JSON text, validated."""
    def to_json(self) -> str:
        """The profile as JSON (the file format of ``save``)."""
    def save(self, path: PathLike) -> None:
        """Writes the profile JSON to ``path`` (a temporary file, then renamed)."""
    @property
    def name(self) -> str:
        """The profile's name."""
    @property
    def length_mm(self) -> float:
        """The bundle's length, mm."""
    @property
    def radius_mm(self) -> float:
        """The bundle's radius, mm."""
    @property
    def source(self) -> Literal["nominal", "calibrated"]:
        """``"nominal"`` (derived from the geometry) or ``"calibrated"`` (fitted)."""
    @property
    def ranges(self) -> Dict[str, Tuple[float, float]]:
        """The calibrated ranges: ``{"h_mm": (min, max), "alpha_rad": ..., "beta_rad": ...}``."""
    def predict(
        self,
        h_mm: ArrayLike,
        alpha_rad: Optional[ArrayLike] = None,
        beta_rad: Optional[ArrayLike] = None,
        *,
        extrapolate: bool = False,
    ) -> Tuple[npt.NDArray[np.float64], npt.NDArray[np.float64], npt.NDArray[np.float64]]:
        """Footprint lengths ``(lt_mm, lh_mm, lr_mm)`` for presses: depth ``h_mm`` (mm), tilt
        ``alpha_rad`` and rotation ``beta_rad`` (radians, default 0), broadcast like numpy;
        each result has the broadcast shape (as ``maobi footprint --json``). Raises
        ``ValueError`` outside the calibrated ranges unless ``extrapolate=True``, outside what
        the brush can do at all (depth 0 to its length, tilt within ±π/2, rotation within
        ±2π) or for a value that is not finite."""

def calibrate(
    measurements: Union[ArrayLike, PathLike],
    *,
    form: Literal["general", "paper"] = "general",
    brush: BrushArg = None,
    name: Optional[str] = None,
) -> Tuple[Brush, Dict[str, Any]]:
    """Fits a brush profile to measured footprints, as ``maobi calibrate``: ``measurements`` an
    ``(N, 6)`` array ``h_mm, alpha_rad, beta_rad, lt_mm, lh_mm, lr_mm`` (radians) or a CSV path
    (``h_mm,alpha_deg,beta_deg,lt_mm,lh_mm,lr_mm``, degrees). ``brush``: whose length and
    radius the profile records (default pen1); ``name``: the profile's name (default the CSV's
    stem, or ``"calibrated"``). Returns ``(brush, report)``, the report as ``maobi calibrate
    --json`` prints it (coefficients, standard errors, R², per output)."""

def render_presses(
    presses: ArrayLike,
    box_mm: BoxMm,
    size_px: int,
    *,
    brush: BrushArg = None,
    model: Literal["bsm", "circle", "ellipse", "line", "qbc"] = "bsm",
    extrapolate: bool = False,
) -> FloatImage:
    """Renders presses with the analytic footprint (B-BSM by default), composed by per-pixel
    maximum: each row of ``presses`` ``(N, 5)`` (``x_mm, y_mm, h_mm, alpha_rad, beta_rad``) a
    footprint whose root end sits at ``(x_mm, y_mm)`` (paper, y down), pointing along
    ``beta_rad`` (root → tip, from +x towards +y); rows with ``h_mm <= 0`` leave nothing.
    ``box_mm``: the paper square shown (a side with its corner at the origin, or
    ``(x0_mm, y0_mm, side_mm)``); returns ``(size_px, size_px)`` float32, ink = 1. Raises
    ``ValueError`` for a press outside the calibrated ranges unless ``extrapolate=True``."""

def render_presses_soft(
    presses: ArrayLike,
    box_mm: BoxMm,
    size_px: int,
    *,
    brush: BrushArg = None,
    edge_px: float = 0.75,
    extrapolate: bool = False,
) -> npt.NDArray[np.float64]:
    """The soft union image ``1 − Π(1 − c_i)`` of the presses' soft footprints (the teardrop
    track refinement optimises, its edge softened over ``edge_px`` px each side), placed as
    ``render_presses`` places them; ``(size_px, size_px)`` float64, ink = 1. Differentiable:
    see ``render_presses_soft_vjp`` and ``maobi.torch.render_presses``."""

def render_presses_soft_vjp(
    presses: ArrayLike,
    box_mm: BoxMm,
    size_px: int,
    grad_image: ArrayLike,
    *,
    brush: BrushArg = None,
    edge_px: float = 0.75,
    extrapolate: bool = False,
) -> Tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]:
    """``(image, grad_presses)``: the soft image and, for ``grad_image`` = ∂L/∂image, the
    ``(N, 5)`` array ∂L/∂(x_mm, y_mm, h_mm, alpha_rad, beta_rad) (per mm, per radian), in
    closed form; zeros for rows with ``h_mm <= 0``."""

def render_track(
    track: Track,
    *,
    size_px: int = 512,
    box_mm: Optional[BoxMm] = None,
    brush: BrushArg = None,
    model: Literal["bsm", "circle", "ellipse", "line", "qbc"] = "bsm",
) -> FloatImage:
    """Renders a track through the forward model of the moving brush, as ``maobi write``
    renders its plan (render.png): ``box_mm`` defaults to the track's character box, ``brush``
    to its brush; ``(size_px, size_px)`` float32, ink = 1."""

def csim(a: ArrayLike, b: ArrayLike) -> float:
    """Cosine similarity of two ``(H, W)`` images (ink = 1), as ``maobi compare``."""

def ssim(a: ArrayLike, b: ArrayLike) -> float:
    """Structural similarity (Gaussian window σ = 1.5) of two ``(H, W)`` images, as ``maobi compare``."""

def iou(a: ArrayLike, b: ArrayLike) -> float:
    """Intersection over union of two ``(H, W)`` images thresholded at 0.5, as ``maobi compare``."""

def compare(a: Union[ArrayLike, PathLike], b: Union[ArrayLike, PathLike]) -> Dict[str, Optional[float]]:
    """Every figure of ``maobi compare --json``: ``csim``, ``ssim``, ``iou``, ``mse`` and
    ``psnr`` (dB; ``None`` for identical images). Paths are read as the CLI reads them."""

def load_image(path: PathLike) -> FloatImage:
    """An image file (PNG or JPEG, dark ink on light paper) as ``maobi compare`` reads it:
    ``(H, W)`` float32, ink = 1."""

def save_image(path: PathLike, image: ArrayLike) -> None:
    """Writes an ``(H, W)`` image (ink = 1, values in [0, 1]) as an 8-bit grey PNG, dark ink on
    white, as ``maobi write`` writes its images."""

class Track:
    """A brush track: strokes of points ``x_mm, y_mm, h_mm, alpha_rad, beta_rad`` on the paper
    (the commanded motion; ``h_mm <= 0`` off the paper), the brush it was made for and, when
    known, the character and its box. Reads and writes ``track.json`` as ``maobi write``."""

    def __init__(
        self,
        strokes: Sequence[ArrayLike],
        *,
        brush: BrushArg = None,
        char: Optional[str] = None,
        box_mm: Optional[BoxMm] = None,
    ) -> None:
        """A track from strokes (``(N, 5)`` arrays), the brush (default pen1), and optionally
        the character and its box ``(x0_mm, y0_mm, side_mm)``."""
    @staticmethod
    def load(path: PathLike) -> Track:
        """Reads a ``track.json`` (a character's or a sheet's), validating its brush."""
    @staticmethod
    def from_json(text: str) -> Track:
        """A track from the JSON text of a ``track.json``."""
    def to_json(self) -> str:
        """The track as ``track.json`` text."""
    def save(self, path: PathLike) -> None:
        """Writes ``track.json`` (a temporary file, then renamed)."""
    @property
    def strokes(self) -> List[npt.NDArray[np.float64]]:
        """The strokes, each ``(N, 5)``: ``x_mm, y_mm, h_mm, alpha_rad, beta_rad`` (copies)."""
    @property
    def brush(self) -> Brush:
        """The brush the track was made for."""
    @property
    def char(self) -> Optional[str]:
        """The character, when recorded."""
    @property
    def box_mm(self) -> Optional[Tuple[float, float, float]]:
        """The character's box ``(x0_mm, y0_mm, side_mm)``, when recorded."""
    @property
    def point_count(self) -> int:
        """The number of points over all strokes."""
    def __len__(self) -> int:
        """The number of strokes."""

class Written:
    """One written character (``maobi.write``)."""

    @property
    def char(self) -> str:
        """The character."""
    @property
    def track(self) -> Track:
        """Its brush track (``track.json``)."""
    @property
    def reference(self) -> FloatImage:
        """The glyph on the character box, ``(size_px, size_px)``, ink = 1 (reference.png)."""
    @property
    def plan(self) -> FloatImage:
        """The track rendered through the forward model (render.png)."""
    @property
    def executed(self) -> FloatImage:
        """What the robot program writes, executed as ``robot send`` sends it (executed.png)."""
    @property
    def report(self) -> Dict[str, Any]:
        """The fields of report.json: ``plan``, ``executed``, ``agreement`` (CSIM, SSIM, IoU),
        ``char_mm`` (box side, mm), ``brush``, ``timing_ms``, ``refine``, ..."""

def write(
    text: str,
    brush: BrushArg = None,
    refine: bool = False,
    size_px: int = 512,
    font: Union[PathLike, Sequence[PathLike], None] = None,
    hanzi_data: Optional[PathLike] = None,
    alpha_rad: float = 0.0,
    *,
    char_mm: Optional[float] = None,
    iters: Optional[int] = None,
    free_widths: bool = False,
) -> Union[Written, List[Written]]:
    """Writes characters as ``maobi write TEXT`` (the same track, renders, executed program and
    report; no files): one :class:`Written` for one character, a list for several (one box
    size for all). ``brush``: a built-in name, a profile path or a :class:`Brush` (default
    pen1); ``refine``: refine each track against its glyph first (``iters`` steps, default 20);
    ``size_px``: each image's side (64–4096); ``font``: glyphs from font files; ``hanzi_data``:
    a hanzi-writer-data folder; ``alpha_rad``: constant tilt, inside the brush's range;
    ``char_mm``: the box side, mm (default: sized for the brush); ``free_widths``: also score the
    plan with free footprint widths (``report["plan"]["free_widths"]``, as ``maobi write
    --free-widths``; off by default: a second track and render). Raises ``ValueError`` for a
    character no source covers, naming ``font``/``hanzi_data``."""

def glyph(
    char: str,
    size_px: int = 512,
    font: Union[PathLike, Sequence[PathLike], None] = None,
    hanzi_data: Optional[PathLike] = None,
) -> FloatImage:
    """The reference image of one character: its glyph on a ``(size_px, size_px)`` em box,
    float32, ink = 1 (``Written.reference``)."""

class Generator:
    """The B-BSMG generator: a press ``(h_mm, alpha_rad, beta_rad)`` to its footprint image
    (``size × size``, ink = 1, ``px_per_mm``, footprint centred), and the exact gradient of an
    image loss back to the press (maobi's ``InputVjp``)."""

    @staticmethod
    def load(path: Optional[PathLike] = None) -> Generator:
        """The generator at ``path`` (``.safetensors`` with its ``.json`` beside it), or the
        committed pen1 generator when ``None``."""
    @property
    def size(self) -> int:
        """Side of the images, px."""
    @property
    def px_per_mm(self) -> float:
        """Scale of the images, px per mm."""
    @property
    def brush(self) -> Brush:
        """The brush the generator was trained for."""
    def forward(self, params: ArrayLike, *, extrapolate: bool = False) -> npt.NDArray[np.float32]:
        """Footprint images ``(B, size, size)`` float32 for ``params`` ``(B, 3)``
        (``h_mm, alpha_rad, beta_rad``). Raises ``ValueError`` outside the trained ranges
        unless ``extrapolate=True``."""
    def vjp(self, params: ArrayLike, grad_images: ArrayLike, *, extrapolate: bool = False) -> npt.NDArray[np.float64]:
        """∂L/∂params ``(B, 3)`` (per mm, per radian) for ``grad_images`` = ∂L/∂images
        ``(B, size, size)``: reverse mode through the network."""

def robot_check(track: Union[Track, PathLike], paper: Union[PathLike, Dict[str, Any]], robot: Union[PathLike, Dict[str, Any], None] = None) -> Dict[str, Any]: ...
def robot_export(
    track: Union[Track, PathLike],
    paper: Union[PathLike, Dict[str, Any]],
    format: str = "urscript",
    robot: Union[PathLike, Dict[str, Any], None] = None,
    *,
    kinematics: Optional[PathLike] = None,
    motion: str = "path-buffer",
    accept_nominal_kinematics: bool = False,
) -> str: ...
def _panic_for_tests() -> None: ...
def _last_call_seconds() -> float: ...
