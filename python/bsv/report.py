"""The report of ``bsv process`` / ``bsv demo``: one self-contained ``report.html`` (every figure inlined as a
``data:`` URI, readable on a phone), the same report as ``report.pdf`` (WeasyPrint) and ``volumes.csv``.

Figures (matplotlib Agg, drawn in memory): the segmented fitted body seen from the front and from the
subject's left side (a flat-shaded painter's-algorithm render of the labelled mesh in the segment
palette of :mod:`bsv.palette`), the cloud over the fitted mesh, the limb volumes and the torso (and head)
volume on their own scales, with their 95 % intervals, and the colourised camera segmentations.
Tables, in plain language: volumes with their 95 % intervals and masses, the true volumes over the same
segments when known (a synthetic subject), proportions, left/right asymmetry ("not distinguishable from
symmetric" when the interval holds 0), landmark and calibration warnings; the technical details (cloud
cleaning per camera, registration figures and parameters, timings) are folded away in ``<details>`` in
report.html and left out of report.pdf, the copy to print (:data:`TECHNICAL_IN_PDF`).
Every file is rendered before any is written, and each is written atomically. The documents are composed
first with their figures still to draw (:class:`ReportJob`); the figures are then drawn once for both files
(``bsv process``: by the PDF worker, which lays report.pdf out, while this process writes the other files
into a staging folder, :mod:`bsv.staging`); report.pdf embeds the shaded renders as JPEG, which WeasyPrint
takes as they are.
"""

from __future__ import annotations

import base64
import csv
import functools
import html
import io
import math
import os
import re
import tempfile
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal

import numpy as np

from . import _bsv, anatomy
from .errors import OutputExistsError
from .palette import colourise, hex_colour, plain_name, rgb01, segment_id
from .pdf import PdfRenderer, render_pdf, require_pdf
from .staging import file_mode
from .types import SEGMENT_NAMES

if TYPE_CHECKING:
    from matplotlib.artist import Artist

PathLike = str | Path
#: The file a report document is rendered for: report.html or report.pdf.
_Target = Literal["html", "pdf"]

#: The files the report writes into its folder.
FILES = ("report.html", "report.pdf", "volumes.csv")

#: Views: (screen x axis, screen y axis, toward-viewer axis) as world direction vectors (DESIGN.md frame:
#: Y up, subject faces +Z, +X = subject's left).
VIEWS = {
    "front": (np.array([1.0, 0.0, 0.0]), np.array([0.0, 1.0, 0.0]), np.array([0.0, 0.0, 1.0])),
    "side": (np.array([0.0, 0.0, -1.0]), np.array([0.0, 1.0, 0.0]), np.array([1.0, 0.0, 0.0])),
    "back": (np.array([-1.0, 0.0, 0.0]), np.array([0.0, 1.0, 0.0]), np.array([0.0, 0.0, -1.0])),
}


def face_labels(faces: np.ndarray, vertex_labels: np.ndarray | None, face_labels_: np.ndarray | None = None) -> np.ndarray:
    """Per-face segment ids: the given face labels, else Rust's one rule
    (``bsv_volume::face_labels_from_vertices``: the label shared by two corners; three different: the
    corner with the smallest vertex index)."""
    if face_labels_ is not None and len(face_labels_) == len(faces):
        return np.asarray(face_labels_, dtype=np.uint8)
    if vertex_labels is None:
        return np.zeros(len(faces), dtype=np.uint8)
    return _bsv.face_labels_from_vertices(faces, vertex_labels)


def render_mesh(ax: Any, vertices: np.ndarray, faces: np.ndarray, labels: np.ndarray | None, view: str = "front",
                alpha: float = 1.0, grey: bool = False) -> None:
    """Draws a labelled mesh on a 2-D matplotlib axis: orthographic projection, faces sorted far to near
    (painter's algorithm), Lambert-shaded palette colours (or grey), each face one flat colour. An opaque
    mesh goes to the renderer in one call (its Gouraud-triangle primitive with the same colour at the three
    corners: adjacent faces meet without seams; half the time of a collection of 4,000 polygons with their
    edges stroked to hide the seams). A translucent one (``alpha`` < 1) stays such a collection: the
    primitive widens each triangle by half a pixel, which doubles the shared edges' opacity. ``alpha`` must lie
    in [0, 1] (a :class:`ValueError` otherwise)."""
    if not 0.0 <= alpha <= 1.0:  # NaN fails too
        raise ValueError(f"render_mesh: alpha must be between 0 and 1, got {alpha!r}")
    sx, sy, toward = VIEWS[view]
    v = np.asarray(vertices, dtype=np.float64)
    f = np.asarray(faces, dtype=np.int64)
    tri = v[f]
    n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-300)
    facing = n @ toward
    light = toward + 0.35 * sy + 0.2 * sx
    light /= np.linalg.norm(light)
    shade = 0.3 + 0.7 * np.clip(n @ light, 0.0, 1.0)
    keep = facing > -0.05  # back faces are hidden anyway: skip them
    depth = (tri @ toward).mean(axis=1)
    order = np.argsort(depth[keep], kind="stable")
    idx = np.flatnonzero(keep)[order]
    xy = np.stack([tri[idx] @ sx, tri[idx] @ sy], axis=-1)
    base = np.full((len(idx), 3), 0.78) if grey else rgb01()[np.clip(np.asarray(labels)[idx], 0, 14)]
    colours = np.clip(base * shade[idx, None], 0.0, 1.0)
    rgba = np.concatenate([colours, np.full((len(idx), 1), alpha)], axis=1)
    if alpha == 1.0:
        ax.add_artist(_flat_triangles_class()(xy, rgba))
    else:
        from matplotlib.collections import PolyCollection

        # matplotlib's stub asks for a Sequence; an (N, 3, 2) array is what PolyCollection handles fastest
        ax.add_collection(PolyCollection(xy, facecolors=rgba, edgecolors=rgba, linewidths=0.15))  # type: ignore[arg-type]
    ax.set_xlim(xy[..., 0].min() - 0.05, xy[..., 0].max() + 0.05)
    ax.set_ylim(xy[..., 1].min() - 0.05, xy[..., 1].max() + 0.05)
    ax.set_aspect("equal")
    ax.set_axis_off()


@functools.cache
def _flat_triangles_class() -> Callable[[np.ndarray, np.ndarray], Artist]:
    """The matplotlib artist class of :func:`render_mesh`, called with the triangles and their colours (made
    on first use: importing this module does not import matplotlib)."""
    from matplotlib.artist import Artist

    class FlatTriangles(Artist):
        """(N, 3, 2) triangles in data coordinates, each filled with one RGBA colour (N, 4), drawn in order."""

        zorder = 1  # where a collection would be: under lines and points

        def __init__(self, xy: np.ndarray, rgba: np.ndarray) -> None:
            super().__init__()
            self._xy = xy
            self._rgba = np.repeat(rgba[:, None, :], 3, axis=1)

        def draw(self, renderer: Any) -> None:
            if not self.get_visible() or not len(self._xy):
                return
            gc = renderer.new_gc()
            if self.get_clip_on():  # clipped like any artist of the axes (to its patch)
                gc.set_clip_rectangle(self.get_clip_box())
                gc.set_clip_path(self.get_clip_path())
            renderer.draw_gouraud_triangles(gc, self._xy, self._rgba, self.get_transform().frozen())
            gc.restore()
            self.stale = False

    return FlatTriangles


def palette() -> np.ndarray:
    """(15, 3) float RGB in [0, 1] of the segment ids (:func:`bsv.palette.rgb01`, Rust's palette)."""
    return rgb01()


#: Dots per inch of every figure (its pixels: figsize x DPI).
FIGURE_DPI = 110
#: JPEG quality of the shaded renders inside report.pdf (chroma kept at full resolution).
PDF_JPEG_QUALITY = 90
#: Longest side (pixels) of a camera segmentation preview: larger label images are shown every n-th pixel
#: (nearest: the ids stay exact). The preview is displayed at most 320 px high.
PREVIEW_MAX_PX = 512


@dataclass(frozen=True, eq=False)
class _Image:
    """One drawn report image, (H, W, 3) uint8 RGB, encoded when a document first asks for it: as PNG in
    report.html and, unless ``jpeg_in_pdf`` (the shaded renders), in report.pdf; with ``jpeg_in_pdf`` as JPEG
    in report.pdf, which WeasyPrint embeds as it is (a PNG it decodes and compresses again). A report without
    report.pdf encodes no JPEG."""

    rgb: np.ndarray
    jpeg_in_pdf: bool = False

    @functools.cached_property
    def _png_uri(self) -> str:
        return _data_uri(_encode(self.rgb, "PNG"))

    @functools.cached_property
    def _jpeg_uri(self) -> str:
        return _data_uri(_encode(self.rgb, "JPEG"), "image/jpeg")

    def src(self, target: _Target) -> str:
        """The image's data: URI in the document for ``target``."""
        return self._jpeg_uri if target == "pdf" and self.jpeg_in_pdf else self._png_uri


def _new_figure(width: float, height: float) -> Any:
    """A matplotlib figure on its own Agg canvas (no pyplot: nothing to close, no global state)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(width, height), dpi=FIGURE_DPI)
    FigureCanvasAgg(fig)
    return fig


def prepare_figures() -> bool:
    """Loads what the first figure needs (matplotlib's figure, Agg canvas, collections and font cache, one
    font, Pillow's PNG and JPEG encoders) by drawing a small chart with a title and encoding it. About half a
    second of a fresh process: the PDF worker of ``bsv process`` runs it while it waits for the report
    (:func:`bsv.pdf.main`); without a worker, ``bsv process`` runs it on a background thread while MediaPipe
    detects (native code that lets Python run), not after the registration. Returns whether it all went
    through; errors are left to the report, which draws the same things and reports them."""
    try:
        fig = _new_figure(1.0, 1.0)
        ax = fig.add_subplot()
        ax.bar([0, 1], [1.0, 2.0], 0.7, color=["#4477aa", "#ee6677"], edgecolor="k", linewidth=0.4)
        ax.errorbar([0, 1], [1.0, 2.0], yerr=[[0.1, 0.1], [0.1, 0.1]], fmt="none", ecolor="k", capsize=2)
        ax.set_title("BSV", fontsize=9)
        fig.tight_layout()
        triangle = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
        render_mesh(fig.add_subplot(), triangle, np.array([[0, 1, 2]]), np.array([1, 1, 1], np.uint8), "front")
        rgb = _pixels(fig)
        _encode(rgb, "PNG")
        _encode(rgb, "JPEG")
    except Exception:  # a warm-up: the report draws the same and names what fails
        return False
    return True


def _pixels(fig: Any) -> np.ndarray:
    """The figure drawn once on its Agg canvas: (H, W, 3) uint8 RGB (the background is opaque white)."""
    fig.canvas.draw()
    return np.ascontiguousarray(np.asarray(fig.canvas.buffer_rgba())[..., :3])


def _encode(rgb: np.ndarray, fmt: Literal["PNG", "JPEG"]) -> bytes:
    """RGB pixels as PNG (zlib's fastest level: about 8 % larger than matplotlib's default, half the time)
    or as JPEG (:data:`PDF_JPEG_QUALITY`, full-resolution chroma); any other ``fmt`` is a ValueError."""
    from PIL import Image as PILImage

    buf = io.BytesIO()
    if fmt == "PNG":
        PILImage.fromarray(rgb).save(buf, format="PNG", compress_level=1)
    elif fmt == "JPEG":
        PILImage.fromarray(rgb).save(buf, format="JPEG", quality=PDF_JPEG_QUALITY, subsampling=0)
    else:
        raise ValueError(f"_encode: fmt must be 'PNG' or 'JPEG', got {fmt!r}")
    return buf.getvalue()


def _image(fig: Any, shaded: bool = False) -> _Image:
    """A drawn figure as a report :class:`_Image` (``shaded``: a render, JPEG in the PDF)."""
    return _Image(_pixels(fig), jpeg_in_pdf=shaded)


def _data_uri(data: bytes, mime: str = "image/png") -> str:
    return f"data:{mime};base64," + base64.b64encode(data).decode("ascii")


def _body_figure(vertices: np.ndarray, faces: np.ndarray, labels: np.ndarray, view: str) -> _Image:
    """The segmented fitted mesh seen from ``view`` (a shaded render: JPEG in report.pdf)."""
    fig = _new_figure(3.0, 5.0)
    ax = fig.add_subplot()
    render_mesh(ax, vertices, faces, labels, view)
    fig.subplots_adjust(bottom=0.01, top=0.99, left=0.01, right=0.99)
    return _image(fig, shaded=True)


#: The most measured points the cloud figure shows (a fixed random subset of a larger cloud).
CLOUD_FIGURE_POINTS = 25_000


def _cloud_sample(cloud: Any, max_points: int = CLOUD_FIGURE_POINTS) -> tuple[np.ndarray, np.ndarray]:
    """The points the cloud figure shows and their segment ids (0-14): all of them, or ``max_points`` drawn
    with a fixed seed (the same figure for the same cloud)."""
    pts = np.asarray(cloud.points)
    lab = np.zeros(len(pts), dtype=np.uint8) if cloud.labels is None else np.asarray(cloud.labels)
    if len(pts) > max_points:
        sel = np.random.default_rng(0).choice(len(pts), max_points, replace=False)
        pts, lab = pts[sel], lab[sel]
    return np.ascontiguousarray(pts, dtype=np.float64), np.clip(lab, 0, 14).astype(np.uint8)


def _cloud_figure(vertices: np.ndarray, faces: np.ndarray, labels: np.ndarray, pts: np.ndarray,
                  lab: np.ndarray) -> _Image:
    """The measured points ``pts`` (segment colours ``lab``, :func:`_cloud_sample`) over the fitted mesh
    (grey), front and left side. The points are one-pixel marks at half opacity, one batch per segment (a
    scatter of 25,000 markers cost 0.15 s a view; these look alike)."""
    pal = rgb01()
    fig = _new_figure(5.6, 5.0)
    axes = fig.subplots(1, 2)
    for ax, view in zip(axes, ("front", "side"), strict=True):
        render_mesh(ax, vertices, faces, labels, view, grey=True)
        sx, sy, _ = VIEWS[view]
        for k in np.unique(lab):
            p = pts[lab == k]
            ax.plot(p @ sx, p @ sy, ",", color=pal[k], alpha=0.5)
        ax.set_title("front" if view == "front" else "left side", fontsize=9)
    fig.subplots_adjust(left=0.02, right=0.98, top=0.94, bottom=0.02, wspace=0.05)
    return _image(fig, shaded=True)


#: Segments drawn on the limb chart (limb scale) and on the torso chart (its own scale).
LIMB_SEGMENTS = tuple(SEGMENT_NAMES[i] for i in range(3, 15))
CENTRAL_SEGMENTS = ("torso", "head")


def _bar_chart(names: Sequence[str], volumes_l: dict[str, float], bands: dict[str, tuple[float, float]],
               truth: dict[str, float] | None, title: str, width: float) -> _Image:
    """Bars of the estimated volumes in palette colours with their 95 % intervals (error bars) and the true
    volume of a synthetic subject (a black tick) when known."""
    x = np.arange(len(names))
    est = np.array([volumes_l[n] for n in names])
    fig = _new_figure(width, 3.0)
    ax = fig.add_subplot()
    ax.bar(x, est, 0.7, color=[rgb01()[segment_id(n)] for n in names], edgecolor="k", linewidth=0.4)
    if any(n in bands for n in names):
        lo = np.array([est[k] - bands[n][0] if n in bands else 0.0 for k, n in enumerate(names)])
        hi = np.array([bands[n][1] - est[k] if n in bands else 0.0 for k, n in enumerate(names)])
        ax.errorbar(x, est, yerr=np.stack([np.maximum(lo, 0), np.maximum(hi, 0)]), fmt="none", ecolor="k",
                    elinewidth=0.8, capsize=2, label="95 % interval")
    if truth:
        tv = np.array([truth.get(n, np.nan) for n in names])
        ax.scatter(x, tv, marker="_", s=160, color="k", linewidths=2, zorder=3, label="true volume")
    if (truth or bands) and len(names) > 2:
        ax.legend(fontsize=7, frameon=False, loc="upper right")
    ax.set_xticks(x)
    ax.set_xticklabels([plain_name(n).replace(" ", "\n", 1) for n in names], fontsize=7,
                       rotation=0 if len(names) <= 2 else 45, ha="center" if len(names) <= 2 else "right")
    ax.set_ylabel("volume (litres)", fontsize=8)
    tops = [float(np.nanmax(est)), *(bands[n][1] for n in names if n in bands),
            *(float(truth[n]) for n in names if truth and n in truth)]
    ax.set_ylim(0, max(tops) * 1.15)
    ax.set_title(title, fontsize=9)
    ax.tick_params(axis="y", labelsize=7)
    ax.spines[["top", "right"]].set_visible(False)
    fig.tight_layout()
    return _image(fig)


def _segmentation_ids(out: Path, segmentations: Mapping[str, np.ndarray] | None) -> dict[str, np.ndarray]:
    """The camera segmentations (raw ids 0-14) by camera: the given label images, else
    ``segmentation/<camera>/segmentation.png`` in OUT."""
    from PIL import Image as PILImage

    if segmentations is not None:
        return {cam: np.asarray(ids) for cam, ids in segmentations.items()}
    found = {}
    for path in sorted(out.glob("segmentation/*/segmentation.png")):
        with PILImage.open(path) as im:
            ids = np.asarray(im)
        if ids.ndim == 2:
            found[path.parent.name] = ids
    return found


def _preview_ids(ids: np.ndarray) -> np.ndarray:
    """A segmentation's ids every n-th pixel, at most :data:`PREVIEW_MAX_PX` on the long side."""
    step = max(1, math.ceil(max(ids.shape[:2]) / PREVIEW_MAX_PX))
    return np.ascontiguousarray(ids[::step, ::step])


def _preview(ids: np.ndarray) -> _Image:
    """A segmentation (reduced by :func:`_preview_ids`) colourised in the palette."""
    return _Image(colourise(ids))


#: What draws each kind of :class:`FigureJob`.
_DRAWERS: dict[str, Callable[..., _Image]] = {
    "body": _body_figure, "cloud": _cloud_figure, "bar": _bar_chart, "preview": _preview}


@dataclass(frozen=True, eq=False)
class FigureJob:
    """One report figure still to draw: its kind (``body``, ``cloud``, ``bar``, ``preview``) and the
    arguments of that kind's drawer, plain data (arrays, numbers, strings) that a worker process can be
    sent (:class:`bsv.pdf.PdfRenderer`)."""

    kind: Literal["body", "cloud", "bar", "preview"]
    args: tuple[Any, ...]

    def draw(self) -> _Image:
        """The figure drawn (matplotlib, in this process)."""
        return _DRAWERS[self.kind](*self.args)


#: How a document of a :class:`ReportJob` marks where a figure goes: ``<img src="bsv-figure:KEY"``.
FIGURE_SRC_PREFIX = "bsv-figure:"
_FIGURE_SRC = re.compile(r'src="' + re.escape(FIGURE_SRC_PREFIX) + r'([^"]+)"')


@dataclass(frozen=True, eq=False)
class ReportJob:
    """A report with its figures still to draw: the figures (:class:`FigureJob` by key) and the documents
    for report.html and report.pdf, where each figure's ``src`` is its key (:data:`FIGURE_SRC_PREFIX`).
    Composing the documents needs no matplotlib; :meth:`documents` draws the figures once and inlines them
    in each document in its format (:meth:`_Image.src`). ``bsv process`` sends it to the PDF worker, which
    draws while this process writes the other files (:meth:`bsv.pdf.PdfRenderer.submit`)."""

    figures: dict[str, FigureJob]
    templates: dict[_Target, str]

    def documents(self, drawn: Mapping[str, _Image] | None = None) -> dict[_Target, str]:
        """Every document with its figures inlined: those of ``drawn`` (drawn before from the same
        :class:`FigureJob`, :func:`mesh_figures`) as they are, the others drawn now."""
        ready = dict(drawn or {})
        images = {key: ready[key] if key in ready else job.draw() for key, job in self.figures.items()}
        return {target: fill_figures(doc, images, target) for target, doc in self.templates.items()}


def draw_ahead(figures: Mapping[str, FigureJob]) -> dict[str, _Image]:
    """``figures`` drawn and encoded for both documents now (:meth:`bsv.pdf.PdfRenderer.prepare`), to be
    passed to :meth:`ReportJob.documents` later."""
    drawn = {key: job.draw() for key, job in figures.items()}
    for img in drawn.values():
        for target in ("html", "pdf"):
            img.src(target)
    return drawn


def mesh_figures(mesh: Any, cloud: Any) -> dict[str, FigureJob]:
    """The report's figures of the fitted ``mesh`` (its segments front and side, and the measured ``cloud``
    over it): all the report needs of the registration's result, so ``bsv process`` has them drawn while
    it computes the intervals (:meth:`bsv.pdf.PdfRenderer.prepare`)."""
    vertices = np.ascontiguousarray(mesh.vertices, dtype=np.float64)
    faces = np.ascontiguousarray(mesh.faces, dtype=np.int64)
    flabels = face_labels(mesh.faces, mesh.vertex_labels, mesh.face_labels)
    return {"front": FigureJob("body", (vertices, faces, flabels, "front")),
            "side": FigureJob("body", (vertices, faces, flabels, "side")),
            "cloud": FigureJob("cloud", (vertices, faces, flabels, *_cloud_sample(cloud)))}


def fill_figures(doc: str, images: Mapping[str, _Image], target: _Target) -> str:
    """``doc`` with each figure's key (:data:`FIGURE_SRC_PREFIX`) replaced by its image's data: URI for
    ``target``; a key without an image is a :class:`KeyError` naming it."""
    def src(m: re.Match[str]) -> str:
        key = m[1]
        if key not in images:
            raise KeyError(f"fill_figures: the document shows figure {key!r}, which was not drawn")
        return f'src="{images[key].src(target)}"'

    return _FIGURE_SRC.sub(src, doc)


def _opt(x: Any, digits: int) -> str:
    return "" if x is None else _fmt(x, digits)


def cleaning_html(cloud_report: dict[str, Any]) -> str:
    """The "Cloud cleaning" section: one row per camera (points removed at each step, the floor check),
    the floor agreement between cameras and the warnings (highlighted)."""
    rows = []
    for v in cloud_report.get("views", []):
        c = v.get("cleaning") or {}
        f = v.get("floor") or {}
        seen = f.get("status") == "seen"
        rows.append([html.escape(str(v.get("name", ""))), v.get("deprojected", ""), c.get("floor_removed", ""),
                     c.get("edge_removed", ""), c.get("far_removed", ""), c.get("separate_removed", ""),
                     v.get("sor_removed", ""), "seen" if seen else "not seen",
                     _opt(f.get("pitch_deg"), 2), _opt(f.get("roll_deg"), 2), _opt(f.get("height_mm"), 1)])
    table = _table(["camera", "mask points", "floor", "edges", "far", "separate", "outliers (SOR)", "floor check",
                    "pitch deg", "roll deg", "floor height mm"], rows)
    agree = [[html.escape(" / ".join(a.get("cameras", []))), _fmt(a.get("tilt_deg"), 2), _fmt(a.get("height_mm"), 1)]
             for a in cloud_report.get("floor_agreement", [])]
    agree_html = _table(["cameras", "floor angle deg", "height difference mm"], agree) if agree else ""
    warnings = cloud_report.get("warnings", [])
    warn_html = ("<ul class=\"warn\">" + "".join(f"<li>{html.escape(str(w))}</li>" for w in warnings) + "</ul>"
                 if warnings else "<p class=\"note\">No calibration warning.</p>")
    return f"<h2>Cloud cleaning</h2>{table}{agree_html}{warn_html}"


def quality_html(registration: dict[str, Any]) -> str:
    """The per-segment fit quality table (``registration["quality"]``, rule in bsv-register quality.rs), in
    plain language; a doubtful segment is marked in red. Empty when the summary has no quality figures."""
    quality: dict[str, dict[str, Any]] = registration.get("quality") or {}
    if not quality:
        return ""
    lim = _bsv.QUALITY_LIMITS
    rows = [[_swatch(name), _fmt(q.get("rms_mm"), 1), _fmt(100 * q.get("coverage", math.nan), 0),
             _fmt(100 * q.get("gap_fraction", math.nan), 0), _fmt(100 * q.get("exposed_uncovered", math.nan), 0),
             _fmt(100 * q.get("folded", math.nan), 0),
             '<span class="warn">doubtful</span>' if q.get("doubtful") else "ok"] for name, q in quality.items()]
    return ("<h2>Fit quality</h2>" + _table(["Segment", "Fit distance, RMS (mm)", "Surface with points near (%)",
                                              "In gaps (%)", "Seen by a camera, no points near (%)", "Folded (%)", "Fit"],
                                             rows)
            + f'<p class="note">Points near: a measured point within 10 mm. Folded: the fitted surface turned over '
              f"itself. A fit is doubtful with an RMS above {lim['rms_mm']:.0f} mm, more than "
              f"{100 * lim['exposed_uncovered']:.0f} % seen without points near, less than {100 * lim['coverage']:.0f} % "
              f"with points near, or more than {100 * lim['folded']:.0f} % folded ({100 * lim['folded_torso']:.0f} % for the "
              "torso, whose fit folds a little at the neck and the crotch, where no point lies): check the measured points of that "
              "segment before using its volume.</p>")


def _doubtful_html(registration: dict[str, Any]) -> str:
    """A highlighted line naming the segments whose fit is doubtful (empty when none is)."""
    bad = [n for n, q in (registration.get("quality") or {}).items() if q.get("doubtful")]
    return (f'<ul class="warn"><li>Doubtful fit of {html.escape(", ".join(plain_name(n) for n in bad))}: see Fit '
            "quality before using these volumes.</li></ul>") if bad else ""


def _landmark_warnings_html(vols: dict[str, Any]) -> str:
    """The volumes JSON's ``warnings`` (landmarks not seen confidently and where they came from), highlighted."""
    warnings = vols.get("warnings") or []
    return ("<ul class=\"warn\">" + "".join(f"<li>{html.escape(str(w))}</li>" for w in warnings) + "</ul>"
            if warnings else "")


def _fmt(x: Any, digits: int = 3) -> str:
    """A number for a table: integers as integers (iteration and point counts), floats to ``digits``."""
    if isinstance(x, bool):
        return "yes" if x else "no"
    if isinstance(x, (int, np.integer)):
        return str(int(x))
    if isinstance(x, (float, np.floating)) and math.isfinite(float(x)):
        return f"{float(x):.{digits}f}"
    if isinstance(x, (list, tuple)) and all(isinstance(v, (int, float)) for v in x):
        return "(" + ", ".join(_fmt(v, digits) for v in x) + ")"
    return html.escape(str(x))


def _table(headers: Sequence[str], rows: Sequence[Sequence[Any]], cls: str = "") -> str:
    """An HTML table in a horizontally scrollable wrapper (never clipped on a narrow screen)."""
    head = "".join(f"<th>{html.escape(h)}</th>" for h in headers)
    body = "".join("<tr>" + "".join(f"<td>{c}</td>" for c in r) + "</tr>" for r in rows)
    return f'<div class="scroll"><table class="{cls}"><thead><tr>{head}</tr></thead><tbody>{body}</tbody></table></div>'


def _swatch(name: str) -> str:
    try:
        colour = hex_colour(segment_id(name))
    except StopIteration:
        return html.escape(plain_name(name))
    return f'<span class="sw" style="background:{colour}"></span>{html.escape(plain_name(name))}'


def _legend_html(names: Sequence[str]) -> str:
    """The segment legend (HTML swatches in the palette colours)."""
    return '<ul class="legend">' + "".join(f"<li>{_swatch(n)}</li>" for n in names) + "</ul>"


#: Member segments of the aggregates of DESIGN.md (``bsv_core::Aggregate::members``; ``whole``, every
#: segment measured, is left out).
AGGREGATE_MEMBERS: dict[str, tuple[str, ...]] = {
    name: tuple(SEGMENT_NAMES[i] for i in ids) for name, ids in _bsv.AGGREGATES.items() if ids}


def like_for_like_truth(volumes_l: dict[str, float], truth: dict[str, float]) -> dict[str, float]:
    """The true volume to set beside each estimate, over the same segments: a segment's own; an aggregate's
    the sum of the true volumes of the segments it holds in the estimate (``whole``: the measured segments
    only, never the full body when head, hands or feet were not measured). Names with no like-for-like
    truth are left out."""
    segments = [n for n in volumes_l if n in SEGMENT_NAMES.values()]
    out = {n: float(truth[n]) for n in segments if n in truth}
    for agg in volumes_l:
        if agg in out or agg in segments:
            continue
        members = segments if agg == "whole" else AGGREGATE_MEMBERS.get(agg, ())
        if members and all(m in out for m in members) and all(m in volumes_l for m in members):
            out[agg] = float(sum(out[m] for m in members))
    return out


def _bands(vols: dict[str, Any]) -> tuple[Any, dict[str, tuple[float, float]]]:
    from .uncertainty import Intervals

    iv = Intervals.from_json(vols["intervals"]) if vols.get("intervals") else None
    bands = {k: (float(v[0]), float(v[1])) for k, v in (iv.volumes_l.items() if iv else [])}
    return iv, bands


def segment_masses(result: Any) -> tuple[dict[str, float], dict[str, float], str]:
    """Mass (kg) and density (kg/m^3) per segment: the segment-specific densities of the biomechanics
    outputs when the result has them (``result.bsip``), else the volume at the report's one density."""
    vols = result.volumes
    b = getattr(result, "bsip", None)
    if b is not None:
        mass = {n: float(s.mass_kg) for n, s in b.segments.items()}
        dens = {n: float(s.mass_kg / (s.volume_l / 1000.0)) for n, s in b.segments.items() if s.volume_l > 0}
        return mass, dens, str(b.density_source)
    d = float(vols.get("density_kg_m3", 1000.0))
    volumes_l = vols.get("volumes_l", {})
    return ({n: float(v) * d / 1000.0 for n, v in volumes_l.items()}, dict.fromkeys(volumes_l, d),
            f"one density for every segment ({d:g} kg/m³)")


def csv_text(result: Any) -> str:
    """``volumes.csv``: one row per segment (then the aggregates): litres, 95 % interval, mass, density and,
    for a synthetic subject, the true volume over the same segments and the difference."""
    vols = result.volumes
    volumes_l = vols.get("volumes_l", {})
    _, bands = _bands(vols)
    mass, dens, _ = segment_masses(result)
    truth = getattr(result, "truth", None)
    same = like_for_like_truth(volumes_l, truth) if truth else {}
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    header = ["segment", "name", "kind", "volume_l", "interval_low_l", "interval_high_l", "mass_kg", "density_kg_m3"]
    w.writerow(header + (["true_volume_l", "difference_pct"] if truth else []))
    for n, v in volumes_l.items():
        kind = "segment" if n in SEGMENT_NAMES.values() else "total"
        members = AGGREGATE_MEMBERS.get(n, tuple(k for k in volumes_l if k in SEGMENT_NAMES.values()))
        m = mass.get(n, sum(mass.get(k, 0.0) for k in members) if kind == "total" else None)
        band = bands.get(n)
        row = [n, plain_name(n), kind, f"{v:.4f}", f"{band[0]:.4f}" if band else "", f"{band[1]:.4f}" if band else "",
               f"{m:.3f}" if m is not None else "", f"{dens[n]:.1f}" if n in dens and kind == "segment" else ""]
        if truth:
            t = same.get(n)
            row += [f"{t:.4f}" if t is not None else "", f"{(v - t) / t * 100:.2f}" if t else ""]
        w.writerow(row)
    return buf.getvalue()


CSS = """*{box-sizing:border-box}
body{font-family:system-ui,-apple-system,"Segoe UI",Roboto,sans-serif;font-size:15px;line-height:1.4;color:#1a1a1a;
margin:0;padding:12px}
main{max-width:1100px;margin:0 auto}
h1{font-size:22px;margin:0 0 4px}h2{font-size:17px;margin:18px 0 6px;border-bottom:1px solid #ddd}
h3{font-size:15px;margin:10px 0 4px}
.scroll{max-width:100%;overflow-x:auto;-webkit-overflow-scrolling:touch}
table{border-collapse:collapse;margin:2px 0 8px;font-size:14px}
td,th{border:1px solid #ccc;padding:3px 8px;text-align:right;white-space:nowrap}
table.prose td{white-space:normal;text-align:left;min-width:6em}
th{background:#f0f0f0}td:first-child,th:first-child{text-align:left}
.figs{display:flex;flex-wrap:wrap;gap:12px;align-items:flex-start}
figure{margin:0;max-width:100%}figure img{display:block;max-width:100%;height:auto}
figcaption{font-size:13px;color:#444}
figure.body{flex:1 1 140px;max-width:300px}figure.narrow{max-width:240px}.body img{width:100%}.seg img{max-height:320px;width:auto}
.key{font-size:17px}.key b{font-size:19px}
.legend{list-style:none;padding:0;margin:4px 0;display:flex;flex-wrap:wrap;gap:4px 14px;font-size:13px}
.sw{display:inline-block;width:12px;height:12px;border:1px solid #555;margin-right:5px;vertical-align:-1px}
.note{color:#555;font-size:13px}.warn{color:#a00000;font-weight:bold}
details{margin:12px 0;border:1px solid #ddd;border-radius:4px;padding:6px 10px}
summary{cursor:pointer;font-weight:bold}
@media print{body{font-size:10pt;padding:0}table{font-size:8pt}td,th{padding:1px 4px}th{white-space:normal}
.scroll{overflow:visible}details{border:none;padding:0}figure{break-inside:avoid}.body img{max-height:330px}}
@page{size:A4;margin:14mm}"""


#: A white 1-pixel PNG (base64) for :func:`warm_up_document`, beside a JPEG it encodes: the decoders a layout uses.
_PIXEL_PNG = ("iVBORw0KGgoAAAANSUhEUgAAAAEAAAABCAIAAACQd1PeAAAADElEQVR4nGP4//8/AAX+Av4N70a4AAAAAElFTkSuQmCC")


def warm_up_document() -> str:
    """A small document shaped like report.pdf's (:data:`CSS`, headings, a table, figures with a PNG and a
    JPEG, notes, a warning, the legend): the PDF worker lays it out while it waits for the report, so that
    the report's first layout finds WeasyPrint's style cascade, fonts, table layout and image decoders warm
    (:func:`bsv.pdf.main`)."""
    jpeg = base64.b64encode(_encode(np.full((8, 8, 3), 255, np.uint8), "JPEG")).decode("ascii")
    figs = (f'<figure class="body"><img src="data:image/png;base64,{_PIXEL_PNG}" alt="png"><figcaption>front'
            f'</figcaption></figure><figure class="seg"><img src="data:image/jpeg;base64,{jpeg}" alt="jpeg">'
            "<figcaption>side</figcaption></figure>")
    return (f'<!DOCTYPE html><html lang="en"><head><meta charset="utf-8"><title>BSV</title><style>{CSS}</style>'
            f'</head><body><main><h1>BSV report</h1><p class="note">Volumes in litres.</p>'
            f'<p class="warn">warning</p><h2>Segments</h2><div class="figs">{figs}</div>'
            '<ul class="legend"><li><span class="sw" style="background:#4477aa"></span>torso</li></ul>'
            "<h2>Volumes</h2><table><tr><th>segment</th><th>volume (L)</th><th>95 % interval</th></tr>"
            "<tr><td>torso</td><td>34.874</td><td>33.934 to 36.048</td></tr></table>"
            '<h3>Left / right</h3><table class="prose"><tr><td>upper arm</td><td>not distinguishable</td></tr>'
            '</table><p class="key"><b>60.4</b> L</p></main></body></html>')


def _figure(key: str, alt: str, caption: str, cls: str = "") -> str:
    """A ``<figure>`` showing figure ``key`` of a :class:`ReportJob` (inlined by :func:`fill_figures`)."""
    return (f'<figure class="{cls}"><img src="{FIGURE_SRC_PREFIX}{html.escape(key)}" alt="{html.escape(alt)}">'
            f"<figcaption>{html.escape(caption)}</figcaption></figure>")


def render_html(result: Any, out_dir: PathLike, title: str = "BSV report",
                segmentations: Mapping[str, np.ndarray] | None = None) -> str:
    """The self-contained report of a :class:`bsv.pipeline.ProcessResult` (figures inlined as data: URIs).
    ``segmentations``: the camera segmentations (label images by camera), shown colourised; without them,
    the ``segmentation/<camera>/segmentation.png`` in ``out_dir``."""
    return _documents(result, out_dir, title, segmentations, ("html",))["html"]


def _documents(result: Any, out_dir: PathLike, title: str, segmentations: Mapping[str, np.ndarray] | None,
               targets: Sequence[_Target]) -> dict[_Target, str]:
    """The report's HTML for each of ``targets`` from one drawing of the figures, in this process: for
    report.html (every image a PNG), for report.pdf (the shaded renders as JPEG; see :class:`_Image`)."""
    return report_job(result, out_dir, title, segmentations, targets).documents()


def report_job(result: Any, out_dir: PathLike, title: str = "BSV report",
               segmentations: Mapping[str, np.ndarray] | None = None,
               targets: Sequence[_Target] = ("html", "pdf"),
               mesh_jobs: Mapping[str, FigureJob] | None = None) -> ReportJob:
    """The report of a :class:`bsv.pipeline.ProcessResult` as a :class:`ReportJob`: its documents for each of
    ``targets`` composed, its figures still to draw. Only the figures' ``src`` differ between the documents
    once drawn. ``segmentations`` as for :func:`render_html`; ``mesh_jobs``: the result's
    :func:`mesh_figures`, made before (and sent to :meth:`bsv.pdf.PdfRenderer.prepare`), else made here."""
    from .uncertainty import asymmetry_text

    out = Path(out_dir)
    mesh = result.registration.mesh
    vols = result.volumes
    volumes_l: dict[str, float] = vols.get("volumes_l", {})
    truth = getattr(result, "truth", None)
    same = like_for_like_truth(volumes_l, truth) if truth else {}
    iv, bands = _bands(vols)
    mass, _, mass_source = segment_masses(result)
    segments = [n for n in (SEGMENT_NAMES[i] for i in range(1, 15)) if n in volumes_l]
    aggregates = [n for n in volumes_l if n not in segments]

    def band(name: str, digits: int = 2) -> str:
        b = bands.get(name) or (iv.ratios.get(name) if iv else None)
        return f"{_fmt(b[0], digits)} to {_fmt(b[1], digits)}" if b else "not computed"

    # Figures
    limbs = [n for n in LIMB_SEGMENTS if n in volumes_l]
    central = [n for n in CENTRAL_SEGMENTS if n in volumes_l]
    seg_ids = _segmentation_ids(out, segmentations)
    figures = dict(mesh_jobs) if mesh_jobs is not None else mesh_figures(mesh, result.cloud)
    truth_l = dict(same) if same else None
    if central:
        figures["torso"] = FigureJob("bar", (central, volumes_l, bands, truth_l, "Torso", 1.9 + 0.6 * len(central)))
    if limbs:
        figures["limbs"] = FigureJob("bar", (limbs, volumes_l, bands, truth_l, "Arms and legs", 5.2))
    figures.update((f"seg:{cam}", FigureJob("preview", (_preview_ids(ids),))) for cam, ids in seg_ids.items())

    # Key numbers
    tl = "trunk_limbs" if "trunk_limbs" in volumes_l else ("whole" if "whole" in volumes_l else None)
    key = ""
    if tl:
        key += (f'<p class="key">{html.escape(plain_name(tl))}: <b>{_fmt(volumes_l[tl], 2)} litres</b>'
                + (f" (95 % interval {band(tl)})" if tl in bands else "") + ".</p>")
    if vols.get("mass_kg") is not None:
        mband = iv.mass_kg.get("mass_trunk_limbs_kg") if iv else None
        key += (f'<p class="key">Estimated mass of the measured segments: <b>{_fmt(vols["mass_kg"], 1)} kg</b>'
                + (f" (torso, arms and legs: 95 % interval {_fmt(mband[0], 1)} to {_fmt(mband[1], 1)} kg)" if mband else "")
                + f'.</p><p class="note">Masses: {html.escape(mass_source)}. Measured segments: '
                + html.escape(", ".join(plain_name(n) for n in segments)) + ".</p>")

    # Volumes table
    headers = ["Segment", "Volume (L)", "95 % interval (L)", "Mass (kg)"]
    if same:
        headers += ["True volume (L)", "Difference %"]
    rows = []
    for n in [*segments, *aggregates]:
        members = AGGREGATE_MEMBERS.get(n, tuple(segments))
        m = mass.get(n) if n in segments else sum(mass.get(k, 0.0) for k in members)
        r = [_swatch(n) if n in segments else f"<b>{html.escape(plain_name(n))}</b>", _fmt(volumes_l[n], 3), band(n, 3),
             _fmt(m, 2)]
        if same:
            t = same.get(n)
            r += [_fmt(t, 3) if t is not None else "", f"{(volumes_l[n] - t) / t * 100:+.2f}" if t else ""]
        rows.append(r)
    vol_table = _table(headers, rows)
    truth_note = ("<p class=\"note\">True volumes: the synthetic subject's own segments; a total is compared over "
                  "the same segments as the estimate (head, hands and feet are not measured).</p>") if same else ""

    ratios = vols.get("ratios", {}) or {}
    ratio_rows = [[html.escape(_ratio_name(k)), _fmt(v, 2), band(k, 2)]
                  for k, v in ratios.items() if not k.startswith("asymmetry_") and v is not None]
    asym_rows = [[html.escape(plain_name(k[len("asymmetry_"):].removesuffix("_pct")).capitalize()),
                  html.escape(asymmetry_text(v, iv.ratios.get(k) if iv else None))]
                 for k, v in ratios.items() if k.startswith("asymmetry_") and v is not None]

    reg = vols.get("registration") or {}
    alerts = f"{key}{_doubtful_html(reg)}{_landmark_warnings_html(vols)}{_warnings_html(result)}"
    iv_note = (f'<p class="note">95 % intervals: {html.escape(iv.method)}.</p>' if iv
               else '<p class="note">No 95 % intervals were computed for this run.</p>')
    asym_html = (_table(["Part", "Left minus right, % of their mean"], asym_rows) if asym_rows
                 else '<p class="note">Not measured.</p>')
    ratio_html = (_table(["Ratio of volumes", "Value", "95 % interval"], ratio_rows) if ratio_rows
                  else '<p class="note">Not measured.</p>')
    bsip_html = _bsip_html(result.bsip) if getattr(result, "bsip", None) is not None else ""
    quality = quality_html(reg)
    tech = _technical_html(result, vols)
    notes = "".join(f"<li>{html.escape(str(n))}</li>" for n in vols.get("notes", []) or [])

    body = (_figure("front", "segmented fitted body, front", "Front", "body")
            + _figure("side", "segmented fitted body, left side", "Left side", "body"))
    charts = ""
    if central:
        charts += _figure("torso", "torso volume", "Torso (own scale)", "narrow")
    if limbs:
        charts += _figure("limbs", "limb volumes", "Arms and legs (own scale)")
    seg_html = ""
    if seg_ids:
        seg_html = ("<h2>Camera segmentation</h2><p class=\"note\">What each camera's image was divided into (the "
                    "raw label images are <code>segmentation/&lt;camera&gt;/segmentation.png</code>, ids 0-14).</p>"
                    '<div class="figs">' + "".join(_figure(f"seg:{cam}", f"{cam} camera segmentation",
                                                           f"{cam} camera", "seg") for cam in seg_ids) + "</div>")
    cloud = _figure("cloud", "measured points over the fitted body",
                    "Measured points (colours: segments) over the fitted body (grey)")

    def page(target: _Target) -> str:
        """The document for ``target``: everything computed above is shared; report.pdf leaves out the
        technical details and describes the boundaries more briefly."""
        return f"""<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><meta name="viewport" content="width=device-width, initial-scale=1">
<title>{html.escape(title)}</title><style>{CSS}</style></head><body><main>
<h1>{html.escape(title)}</h1>
<p class="note">Body segment volumes from two depth cameras (bsv {html.escape(str(vols.get('bsv_version', '')))}).
Volumes in litres, masses in kilograms; 95 % intervals give the range the true value lies in with 95 % confidence.</p>
{alerts}
<h2>Segments</h2>
<div class="figs">{body}</div>
{_legend_html(segments)}
<h2>Volumes</h2>
<div class="figs">{charts}</div>
{vol_table}{truth_note}
{iv_note}
<h2>Left / right</h2>{asym_html}
<h2>Proportions</h2>{ratio_html}
{definitions_html(vols, target)}
{quality}
{bsip_html}
{seg_html}
<h2>Fit to the measured points</h2>
<div class="figs">{cloud}</div>
{tech if target == "html" else TECHNICAL_IN_PDF}
{f"<h2>Notes</h2><ul>{notes}</ul>" if notes else ""}
</main></body></html>
"""

    return ReportJob(figures, {target: page(target) for target in targets})


def definitions_html(vols: dict[str, Any], target: _Target = "html") -> str:
    """What bounds each segment (:mod:`bsv.anatomy`): the joint loops between segments, as measured on the
    template, the template this result was fitted with and how its boundaries were placed (its label
    source), from a volumes report. In report.pdf the loops are named, not described (their table's text
    cost WeasyPrint 0.18 s of layout, 6 % of ``bsv process``): the description is in report.html."""
    reg = vols.get("registration") or {}
    source = str((reg.get("params") or {}).get("labels", ""))
    how = anatomy.LABEL_SOURCE_TEXT.get(source)
    kind = (vols.get("template") or {}).get("kind")
    lead = (f"Segment boundaries in this result: {html.escape(how)}. " if how else "")
    gender = (vols.get("template") or {}).get("gender")
    if gender is not None:
        lead += f"Template: the MakeHuman body of gender {float(gender):.2f} (0 female, 1 male; the sex read from the capture). "
    elif kind:
        lead += f"Template: {html.escape(anatomy.TEMPLATE_TEXT.get(kind, str(kind)))}. "
    if isinstance(vols.get("sex"), dict):
        from .frontend.sex import describe

        lead += html.escape(describe(vols["sex"]), quote=False) + " "
    if vols.get("boundaries_m"):
        lead += ("The thighs' loops with the torso were pulled to the height the crotch in the depth images gives "
                 "them. ")
    pose = (vols.get("template") or {}).get("pose")
    if isinstance(pose, dict) and pose:
        lead += ("Posed like the subject before the fit, from the measured joints: arms "
                 f"{pose.get('arm_down_l', 0):.0f} / {pose.get('arm_down_r', 0):.0f} deg below horizontal (left / right), "
                 f"elbows flexed {pose.get('elbow_l', 0):.0f} / {pose.get('elbow_r', 0):.0f} deg, legs "
                 f"{pose.get('hip_abduction_l', 0):.0f} / {pose.get('hip_abduction_r', 0):.0f} deg out. ")
    if target == "pdf":
        loops = ", ".join(b.joint for b in anatomy.BOUNDARIES.values())
        return ("<h2>Segment definitions</h2>"
                f'<p class="note">{lead}Each boundary is a closed loop of the body surface at a joint ({loops}); '
                "where each loop runs: report.html, \"Segment definitions\".</p>")
    rows = [[html.escape(c) for c in r] for r in anatomy.boundary_rows()]
    whose = ("The template's segments" if source != "cloud" else
             "The template's segments (this result's boundaries follow the measured labels instead)")
    return ("<h2>Segment definitions</h2>"
            f'<p class="note">{lead}{whose}: each boundary is a closed loop of the body surface at a joint, each '
            "point belonging to the segment whose joints move it most. Where the loops run:</p>"
            + _table(["Boundary", "Between", "Where the loop runs",
                      ("On the average template: mm from the joint centre along the limb (+ = towards the hand "
                      "or foot)")], rows, cls="prose"))


def _bsip_html(b: Any) -> str:
    """The body-segment inertial parameters (``bsv process --bsip``): per segment mass, its share of the
    body mass, length and centre of mass beside de Leva's (1996) values, the radii of gyration folded away."""
    def pair(ours: float, theirs: float | None) -> str:
        return f"{ours:.1f}" + ("" if theirs is None else f" ({theirs:.1f})")

    rows, rg_rows = [], []
    for s in b.segments.values():
        r = s.reference
        rows.append([_swatch(s.name), _fmt(s.mass_kg, 2), pair(s.mass_pct, r.mass_pct if r else None),
                     f"{s.length_m * 1e3:.0f}", pair(s.com_pct, r.com_pct if r else None)])
        ref_rg = (r.rg_sagittal_pct, r.rg_transverse_pct, r.rg_longitudinal_pct) if r else (None, None, None)
        rg_rows.append([html.escape(plain_name(s.name)),
                        *(pair(x, y) for x, y in zip(s.radii_of_gyration_pct(), ref_rg, strict=True))])
    return ("<h2>Segment masses and centres of mass</h2>"
            + _table(["Segment", "Mass (kg)", "% of body mass", "Length (mm)", "Centre of mass, % of length"], rows)
            + f'<p class="note">In brackets: de Leva (1996), {html.escape(str(b.sex))}. Body-mass estimate '
            f"{b.body_mass_kg:.1f} kg ({html.escape(str(b.mass_basis))}); densities: {html.escape(str(b.density_source))}."
            " Full values (inertia tensors, joint centres): bsip.json, bsip.csv, model.osim.</p>"
            "<details><summary>Radii of gyration (% of segment length)</summary>"
            + _table(["Segment", "sagittal", "transverse", "longitudinal"], rg_rows) + "</details>")


def _ratio_name(key: str) -> str:
    side = {"l": "left", "r": "right"}.get(key.rsplit("_", 1)[-1], "")
    stem = key.rsplit("_", 1)[0] if side else key
    parts = stem.split("_to_")
    if len(parts) == 2:
        a, b = (p.replace("shin", "lower leg").replace("_", " ") for p in parts)
        return f"{a.capitalize()} / {b} ({side})" if side else f"{a.capitalize()} / {b}"
    return key.replace("_", " ")


def _warnings_html(result: Any) -> str:
    warnings = (getattr(result, "cloud_report", None) or {}).get("warnings", [])
    return ('<ul class="warn">' + "".join(f"<li>{html.escape(str(w))}</li>" for w in warnings) + "</ul>") if warnings else ""


#: Plain-language names of the registration summary's figures (the keys stay in volumes.json).
REGISTRATION_LABELS = {
    "rms_mesh_to_points_mm": "fit distance, body to points (RMS, mm)",
    "rms_points_to_mesh_mm": "fit distance, points to body (RMS, mm)",
    "iterations": "iterations", "seconds": "time (s)", "labels_from": "segment labels taken from",
    "extremities_dropped": "points of head, hands and feet left out", "outliers_removed": "stray points removed",
    "detached_removed": "detached parts removed", "setup_seconds": "set-up time (s)", "total_seconds": "total time (s)",
}


#: What report.pdf, the copy to print and hand over, says in place of the technical details: they are in
#: report.html (folded away) and volumes.json. Two pages of parameter tables would also cost WeasyPrint
#: 0.2-0.3 s of its 0.6 s layout.
TECHNICAL_IN_PDF = ('<p class="note">Technical details (points per camera, cloud cleaning, segmentation, '
                    "registration figures and parameters, timings): report.html and volumes.json.</p>")


def _technical_html(result: Any, vols: dict[str, Any]) -> str:
    """The technical details, folded away: cloud per camera, cloud cleaning, registration figures and
    parameters, segmentation sources, timings."""
    reg = vols.get("registration") or {}
    reg_rows = [[html.escape(REGISTRATION_LABELS.get(k, k.replace("_", " "))), _fmt(v, 2)]
                for k, v in reg.items() if isinstance(v, (int, float, str)) and not isinstance(v, bool)]
    params = reg.get("params") or {}
    param_rows = [[html.escape(k), _fmt(v, 4) if isinstance(v, float) else _fmt(v)] for k, v in params.items()]
    pre = reg.get("prealign") or {}
    pre_rows = [[html.escape(k.replace("_", " ")), _fmt(v, 3)] for k, v in pre.items()]
    cr = getattr(result, "cloud_report", None) or {"views": [], "warnings": []}
    cloud_rows = [[html.escape(str(v.get("name", ""))), _fmt(v.get("mask_pixels", "")), _fmt(v.get("deprojected", "")),
                   _fmt(v.get("sor_removed", "")), _fmt(sum((v.get("dropped") or {}).values())), _fmt(v.get("kept", ""))]
                  for v in cr.get("views", [])]
    seg_rows = [[html.escape(k), html.escape(str(s.get("source", ""))), _fmt(s.get("labelled_pixels", ""))]
                for k, s in (getattr(result, "segmentation", None) or {}).items()]
    timing_rows = [[html.escape(k), _fmt(float(v), 2)] for k, v in (getattr(result, "timings", None) or {}).items()]
    parts = [f"<p>{_fmt(len(result.cloud))} measured points.</p>"]
    if cloud_rows:
        parts.append("<h3>Points per camera</h3>" + _table(
            ["camera", "person mask (px)", "points", "outliers removed (SOR)", "dropped", "kept"], cloud_rows))
        parts.append(cleaning_html(cr).replace("<h2>", "<h3>").replace("</h2>", "</h3>"))
    if seg_rows:
        parts.append("<h3>Segmentation</h3>" + _table(["camera", "source", "labelled px"], seg_rows))
    if reg_rows:
        parts.append("<h3>Registration</h3>" + _table(["", ""], reg_rows))
    if pre_rows:
        parts.append("<h3>Pre-alignment</h3>" + _table(["", ""], pre_rows))
    if param_rows:
        parts.append("<h3>Registration parameters</h3>" + _table(["parameter", "value"], param_rows))
    if timing_rows:
        parts.append("<h3>Timings (s)</h3>" + _table(["step", "s"], timing_rows))
    return "<details><summary>Technical details</summary>" + "".join(parts) + "</details>"


def _write_atomic(path: Path, data: bytes) -> None:
    """Writes ``data`` into a temporary file beside ``path`` and renames it onto ``path``."""
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    try:
        with os.fdopen(fd, "wb") as f:
            f.write(data)
        os.chmod(tmp, file_mode())  # a report is read by others: the usual file mode, not mkstemp's 0600
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def render_report(result: Any, out_dir: PathLike, *, title: str = "BSV report", pdf: bool = True,
                  segmentations: Mapping[str, np.ndarray] | None = None,
                  pdf_renderer: PdfRenderer | None = None,
                  mesh_jobs: Mapping[str, FigureJob] | None = None) -> dict[str, tuple[Path, bytes]]:
    """The report's files rendered in memory, nothing written: {key: (path, bytes)} for ``report.html``
    (self-contained), ``report.pdf`` (unless ``pdf`` is False) and ``volumes.csv`` (keys: report, report_pdf,
    volumes_csv). Write them with :func:`write_rendered`. The figures are drawn once for both files (report.pdf
    takes the shaded renders as JPEG).

    With a ``pdf_renderer`` (and ``pdf``), only volumes.csv is returned: the report (a :class:`ReportJob`) goes
    to the renderer, whose worker process draws the figures and lays report.pdf out while this process goes
    on; :meth:`bsv.pdf.PdfRenderer.report` then returns report.html's and report.pdf's contents.
    ``mesh_jobs``: the fitted mesh's figures as sent to that renderer's :meth:`~bsv.pdf.PdfRenderer.prepare`
    (:func:`report_job`)."""
    out = Path(out_dir)
    files = {"volumes_csv": (out / "volumes.csv", csv_text(result).encode("utf-8"))}
    job = report_job(result, out, title, segmentations, ("html", "pdf") if pdf else ("html",), mesh_jobs)
    if pdf and pdf_renderer is not None:
        pdf_renderer.submit(job)
        return files
    docs = job.documents()
    files["report"] = (out / "report.html", docs["html"].encode("utf-8"))
    if pdf:
        files["report_pdf"] = (out / "report.pdf", render_pdf(docs["pdf"]))
    return files


def check_outputs(paths: Sequence[Path], overwrite: bool) -> None:
    """Refuses (:class:`bsv.errors.OutputExistsError`) existing report files unless ``overwrite``."""
    existing = [p.name for p in paths if p.exists() or p.is_symlink()]
    if existing and not overwrite:
        folder = Path(paths[0]).parent
        raise OutputExistsError(f"{folder} already holds {', '.join(existing)}; pass overwrite=True to replace them")


def write_rendered(files: Mapping[str, tuple[Path, bytes]], overwrite: bool = False) -> dict[str, Path]:
    """Writes rendered report files (:func:`render_report`), each atomically; returns their paths."""
    check_outputs([p for p, _ in files.values()], overwrite)
    for p, data in files.values():
        p.parent.mkdir(parents=True, exist_ok=True)
        _write_atomic(p, data)
    return {k: p for k, (p, _) in files.items()}


def write_report(result: Any, out_dir: PathLike, *, title: str = "BSV report", overwrite: bool = False,
                 pdf: bool = True, segmentations: Mapping[str, np.ndarray] | None = None) -> dict[str, Path]:
    """Writes ``report.html`` (self-contained), ``report.pdf`` (unless ``pdf`` is False) and ``volumes.csv``
    for a :class:`bsv.pipeline.ProcessResult`; returns their paths (keys: report, report_pdf, volumes_csv).
    Everything is rendered before anything is written, and each file is written atomically. Refuses to
    replace existing files unless ``overwrite`` (checked before the rendering)."""
    out = Path(out_dir)
    check_outputs([out / n for n in FILES if pdf or n != "report.pdf"], overwrite)
    if pdf:
        require_pdf()
    return write_rendered(render_report(result, out, title=title, pdf=pdf, segmentations=segmentations), overwrite)


__all__ = [
    "AGGREGATE_MEMBERS",
    "CLOUD_FIGURE_POINTS",
    "CSS",
    "FIGURE_DPI",
    "FIGURE_SRC_PREFIX",
    "FILES",
    "PDF_JPEG_QUALITY",
    "PREVIEW_MAX_PX",
    "TECHNICAL_IN_PDF",
    "VIEWS",
    "FigureJob",
    "ReportJob",
    "check_outputs",
    "cleaning_html",
    "csv_text",
    "draw_ahead",
    "face_labels",
    "fill_figures",
    "like_for_like_truth",
    "mesh_figures",
    "palette",
    "quality_html",
    "render_html",
    "render_mesh",
    "render_pdf",
    "render_report",
    "report_job",
    "require_pdf",
    "segment_masses",
    "write_rendered",
    "write_report",
]
