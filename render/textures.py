"""Procedural textures, generated from a seed (no asset downloads).

Every function is pure: ``(parameters, numpy Generator) -> uint8 image``. Images are returned
with **row index increasing with the texture coordinate t** (OpenGL order); the scene module
hands them to pyrender, which flips rows on upload, after flipping them back.

Two kinds of texture:

- *macro* colour textures mapped by each mesh's UVs (fields around the airport, runway tiles
  with their markings, taxiway and road strips);
- *detail* textures, tileable, neutral grey on average (128), multiplied in the shader at a
  fixed size in metres (grass blades, asphalt grain, concrete). They add the fine grain that
  the macro textures cannot hold, and fade to neutral with mipmapping at distance.
"""
from __future__ import annotations

import math

import numpy as np

from visland.runway import Runway

from .markings import MarkingLayout

__all__ = [
    "tileable_noise", "grass_detail", "pavement_detail", "cloud_texture", "fields_texture",
    "runway_tile", "strip_texture", "coverage_of_rectangles", "coverage_of_polygons", "pre_threshold_tile",
    "runway_patches", "SURFACE_COLOURS", "SURROUNDING_COLOURS",
]

#: Base colours (sRGB 0-255) of the pavements and paints.
SURFACE_COLOURS = {
    "asphalt": (84.0, 84.0, 86.0),
    "concrete": (168.0, 165.0, 158.0),
    "taxiway_asphalt": (92.0, 91.0, 90.0),
    "apron_concrete": (160.0, 157.0, 150.0),
    "road_asphalt": (78.0, 78.0, 80.0),
    "paint_white": (236.0, 236.0, 232.0),
    "paint_yellow": (222.0, 184.0, 40.0),
    "rubber": (28.0, 28.0, 30.0),
}


def tileable_noise(shape, rng: np.random.Generator, beta: float = 2.0, cutoff: float = 0.0) -> np.ndarray:
    """Periodic fractal noise of zero mean and unit standard deviation.

    White noise filtered in the Fourier domain by ``1 / f^(beta/2)`` (power spectrum
    ``1/f^beta``); periodic, so it tiles without seams.

    Parameters
    ----------
    shape : (rows, cols)
    rng : seeded ``numpy.random.Generator`` of the white noise.
    beta : spectral slope (0 white, 2 brownian-like, larger smoother).
    cutoff : frequencies below this (cycles per image) are removed.
    """
    rows, cols = shape
    white = rng.standard_normal((rows, cols))
    fy = np.fft.fftfreq(rows)[:, None] * rows
    fx = np.fft.rfftfreq(cols)[None, :] * cols
    f = np.hypot(fx, fy)
    f[0, 0] = 1.0
    gain = f ** (-beta / 2.0)
    gain[f < max(cutoff, 1e-9)] = 0.0
    gain[0, 0] = 0.0
    field = np.fft.irfft2(np.fft.rfft2(white) * gain, s=(rows, cols))
    # NumPy's SIMD reductions round differently with the array's memory alignment: round the
    # statistics and the field so that every process builds bit-identical textures
    std = _stable(field.std())
    return np.round(field / std if std > 0 else field, 5)


def _stable(value: float) -> float:
    """``value`` rounded to 7 significant digits (last-bit differences between processes vanish)."""
    return float(f"{float(value):.7g}")


def _to_uint8(image) -> np.ndarray:
    return np.clip(np.rint(image), 0, 255, dtype=np.float32 if image.dtype == np.float32 else None).astype(np.uint8)


def grass_detail(rng: np.random.Generator, size: int = 1024) -> np.ndarray:
    """Tileable grass detail (neutral grey mean 128 with a slight green/yellow play).

    Parameters
    ----------
    rng : numpy.random.Generator
        Seeded generator (same seed, same texture in every process).
    size : int, default 1024
        Texels per side.

    Returns
    -------
    ndarray, shape (size, size, 3), uint8
    """
    coarse = tileable_noise((size, size), rng, beta=2.6)
    fine = tileable_noise((size, size), rng, beta=0.6)
    blades = tileable_noise((size, size), rng, beta=1.2, cutoff=size / 8)
    lum = 1.0 + 0.10 * coarse + 0.10 * fine + 0.08 * blades
    hue = 0.05 * tileable_noise((size, size), rng, beta=2.2)
    out = np.stack([lum * (1.0 + hue), lum, lum * (1.0 - 0.5 * hue)], axis=-1) * 128.0
    return _to_uint8(out)


def pavement_detail(rng: np.random.Generator, size: int = 512, joints_every_px: int = 0) -> np.ndarray:
    """Tileable pavement grain, neutral grey mean ~128, (size, size, 3).

    Parameters
    ----------
    rng : numpy.random.Generator
        Seeded generator of the grain.
    size : int, default 512
        Texels per side.
    joints_every_px : int, default 0
        When positive, darker slab joints (concrete) every that many texels.

    Returns
    -------
    ndarray, shape (size, size, 3), uint8
    """
    grain = tileable_noise((size, size), rng, beta=0.3)
    mottle = tileable_noise((size, size), rng, beta=2.8)
    lum = 1.0 + 0.07 * grain + 0.06 * mottle
    # sparse light aggregate stones
    stones = rng.random((size, size)) < 0.01
    lum = lum + 0.18 * stones
    if joints_every_px:
        idx = np.arange(size)
        joint = (idx % joints_every_px) == 0
        lum[joint, :] *= 0.72
        lum[:, joint] *= 0.72
    lum = np.round(lum / _stable(lum.mean()), 5)
    return _to_uint8(np.repeat((lum * 128.0)[..., None], 3, axis=-1))


def cloud_texture(rng: np.random.Generator, size: int = 512) -> np.ndarray:
    """Tileable cloud density in [0, 255] (single channel replicated to RGB).

    Parameters
    ----------
    rng : numpy.random.Generator
        Seeded generator of the density.
    size : int, default 512
        Side in texels.

    Returns
    -------
    ndarray, shape (size, size, 3), uint8
    """
    density = tileable_noise((size, size), rng, beta=3.0) + 0.35 * tileable_noise((size, size), rng, beta=1.8)
    density = np.round((density - density.min()) / (density.max() - density.min()), 5)
    return _to_uint8(np.repeat((density * 255.0)[..., None], 3, axis=-1))


# --------------------------------------------------------------------------- fields
_FIELD_PALETTE = np.array([
    (92, 122, 52), (112, 138, 58), (136, 146, 74), (168, 152, 96), (186, 166, 104),
    (122, 100, 72), (104, 86, 64), (78, 104, 46), (146, 140, 88), (98, 128, 70),
], dtype=float)

#: Per surroundings (SceneParams.surroundings): field palette, airport grass, woods colour and
#: the fractions of woods and built-up patches among the fields.
SURROUNDING_COLOURS = {
    "green": (_FIELD_PALETTE, (104.0, 138.0, 66.0), (46.0, 66.0, 34.0), 0.10, 0.03),
    "dry": (np.array([(188, 168, 110), (170, 150, 96), (202, 182, 124), (150, 132, 88), (178, 160, 112),
                      (160, 146, 100), (196, 176, 132)], dtype=float), (176, 160, 104), (92, 96, 60), 0.06, 0.03),
    "sand": (np.array([(206, 186, 146), (196, 176, 136), (216, 196, 158), (186, 166, 126), (200, 184, 150)],
                      dtype=float), (198, 180, 140), (120, 112, 80), 0.03, 0.02),
    "snow": (np.array([(236, 239, 243), (226, 229, 236), (241, 243, 247), (214, 218, 226), (230, 232, 238)],
                      dtype=float), (232, 235, 240), (52, 62, 56), 0.12, 0.03),
    "urban": (_FIELD_PALETTE, (104.0, 138.0, 66.0), (46.0, 66.0, 34.0), 0.06, 0.70),
}


def fields_texture(rng: np.random.Generator, size: int, extent_m: float, centre_xy_m, airport_rect_m,
                   angle_deg: float = 17.0, surroundings: str = "green") -> np.ndarray:
    """Patchwork of fields, woods and hedges around an airport of mown grass, (size, size, 3).

    Parameters
    ----------
    rng : seeded ``numpy.random.Generator`` of the pattern.
    size : texels per side.
    extent_m : metres covered per side; texel (row, col) centre is at
        ``x = x_c - extent/2 + (col + 0.5) extent/size``, ``y = y_c - extent/2 + (row + 0.5) extent/size``.
    centre_xy_m : (x_c, y_c) runway-frame centre of the texture.
    airport_rect_m : (x0, x1, y0, y1) area of mown grass around the runway.
    angle_deg : direction of the field pattern relative to the runway.
    surroundings : a key of :data:`SURROUNDING_COLOURS` (``urban``: mostly built-up blocks).
    """
    palette, grass_rgb, woods_rgb, woods_frac, built_frac = SURROUNDING_COLOURS[surroundings]
    texel = extent_m / size
    coords = ((np.arange(size) + 0.5) * texel - extent_m / 2.0).astype(np.float32)
    x = np.float32(centre_xy_m[0]) + coords[None, :]
    y = np.float32(centre_xy_m[1]) + coords[:, None]
    a = math.radians(angle_deg)
    # field grid coordinates: rotated, offset so the pattern does not align with the runway
    u = (x * math.cos(a) + y * math.sin(a)) + np.float32(5.0 * extent_m)
    v = (-x * math.sin(a) + y * math.cos(a)) + np.float32(5.0 * extent_m)
    n_strips = int(11 * extent_m / 120.0) + 2
    widths = rng.uniform(120.0, 420.0, n_strips)
    strip_edges = np.concatenate([[0.0], np.cumsum(widths)]).astype(np.float32)
    strip = np.clip(np.searchsorted(strip_edges, u.ravel()).reshape(u.shape) - 1, 0, n_strips - 1)
    n_fields = int(11 * extent_m / 160.0) + 2
    lengths = rng.uniform(160.0, 650.0, (n_strips, n_fields))
    field_edges = np.concatenate([np.zeros((n_strips, 1)), np.cumsum(lengths, axis=1)], axis=1)
    offsets = rng.uniform(0.0, 400.0, n_strips).astype(np.float32)
    vv = v + offsets[strip]
    # fields of every strip share one sorted array: strip k's edges are shifted by k * 1e7 m
    flat_edges = (field_edges + (np.arange(n_strips) * 1e7)[:, None]).ravel()
    field = np.searchsorted(flat_edges, (vv + strip * 1e7).ravel()).reshape(u.shape) - 1 - strip * (n_fields + 1)
    field = np.clip(field, 0, n_fields - 1)
    field_id = strip * n_fields + field
    n_ids = n_strips * n_fields
    # per-field colour; woods (10 %) and built-up patches (3 %) get their own look below
    colours = (palette[rng.integers(0, len(palette), n_ids)]
               * rng.uniform(0.9, 1.08, n_ids)[:, None]).astype(np.float32)
    kind = rng.random(n_ids)
    image = colours[field_id]
    # within-field texture: furrows along the strip direction and large-scale soil variation
    soil = tileable_noise((size, size), rng, beta=2.4).astype(np.float32)
    shade = 1.0 + np.sin(u * np.float32(2 * math.pi / 18.0)) * np.float32(0.035) + np.float32(0.06) * soil
    image *= shade[..., None]
    woods = kind[field_id] < woods_frac
    blotch = tileable_noise((size, size), rng, beta=1.4).astype(np.float32)
    image[woods] = np.array(woods_rgb, np.float32) * (1.0 + 0.18 * blotch[woods])[:, None]
    built = (kind[field_id] >= woods_frac) & (kind[field_id] < woods_frac + built_frac)
    speck = rng.random(int(built.sum())).astype(np.float32)
    roofs = np.where(speck[:, None] < 0.35, np.array([150.0, 92.0, 76.0], np.float32),
                     np.array([128.0, 126.0, 118.0], np.float32))
    image[built] = roofs * (0.85 + 0.3 * speck[:, None])
    # mown airport grass, with mowing stripes
    x0, x1, y0, y1 = airport_rect_m
    inside = (x >= x0) & (x <= x1) & (y >= y0) & (y <= y1)
    mowing = 1.0 + (np.floor((y - y0) / 12.0) % 2) * 0.035 + 0.05 * soil
    grass = np.array(grass_rgb, np.float32)[None, None, :] * np.broadcast_to(mowing, inside.shape)[..., None]
    image[inside] = grass[inside]
    return _to_uint8(image)


# --------------------------------------------------------------------------- runway tiles
def coverage_of_polygons(polygons_m, x_edges_m, y_edges_m, oversample: int = 4) -> np.ndarray:
    """Area fraction of each texel covered by polygons ((n, 2) arrays of x, y in metres), (rows, cols).

    Rasterised with ``cv2.fillPoly`` at ``oversample`` x ``oversample`` sub-texels (sub-pixel
    vertices, 8 fractional bits) and averaged: the coverage is exact to about ``1 / oversample``
    of a texel along the edges. Texels must be evenly spaced.

    Parameters
    ----------
    polygons_m : sequence of ndarray, shape (k, 2)
        Polygon vertices ``(x, y)`` in the runway frame, metres.
    x_edges_m, y_edges_m : ndarray
        Texel edges along x (cols + 1) and y (rows + 1), metres, evenly spaced.
    oversample : int, default 4
        Sub-texels per texel side.

    Returns
    -------
    ndarray, shape (rows, cols)
        Coverage in [0, 1].
    """
    import cv2
    rows, cols = len(y_edges_m) - 1, len(x_edges_m) - 1
    dx = (x_edges_m[-1] - x_edges_m[0]) / cols
    dy = (y_edges_m[-1] - y_edges_m[0]) / rows
    mask = np.zeros((rows * oversample, cols * oversample), np.uint8)
    shift = 8
    pts = []
    for poly in polygons_m:
        poly = np.asarray(poly, dtype=float)
        # sub-texel coordinates whose integer values are sub-texel centres
        u = (poly[:, 0] - x_edges_m[0]) / dx * oversample - 0.5
        v = (poly[:, 1] - y_edges_m[0]) / dy * oversample - 0.5
        pts.append(np.rint(np.stack([u, v], axis=1) * (1 << shift)).astype(np.int32))
    if pts:
        cv2.fillPoly(mask, pts, 255, lineType=cv2.LINE_8, shift=shift)
    return mask.reshape(rows, oversample, cols, oversample).mean(axis=(1, 3)) / 255.0


def coverage_of_rectangles(rects_m, x_edges_m, y_edges_m) -> np.ndarray:
    """Exact area fraction of each texel covered by the union-free sum of axis-aligned rectangles.

    Parameters
    ----------
    rects_m : (n, 4) ``x0, x1, y0, y1``.
    x_edges_m : (cols + 1,) texel edges along x.
    y_edges_m : (rows + 1,) texel edges along y.

    Returns
    -------
    coverage : (rows, cols) float in [0, 1] (overlapping rectangles are clipped to 1).
    """
    x_lo, x_hi = x_edges_m[:-1], x_edges_m[1:]
    y_lo, y_hi = y_edges_m[:-1], y_edges_m[1:]
    out = np.zeros((len(y_lo), len(x_lo)))
    for x0, x1, y0, y1 in np.asarray(rects_m, dtype=float).reshape(-1, 4):
        if x1 <= x_edges_m[0] or x0 >= x_edges_m[-1] or y1 <= y_edges_m[0] or y0 >= y_edges_m[-1]:
            continue
        cx = np.clip(np.minimum(x1, x_hi) - np.maximum(x0, x_lo), 0.0, None) / (x_hi - x_lo)
        cy = np.clip(np.minimum(y1, y_hi) - np.maximum(y0, y_lo), 0.0, None) / (y_hi - y_lo)
        ix = np.nonzero(cx)[0]
        iy = np.nonzero(cy)[0]
        out[iy[0]:iy[-1] + 1, ix[0]:ix[-1] + 1] += np.outer(cy[iy[0]:iy[-1] + 1], cx[ix[0]:ix[-1] + 1])
    return np.minimum(out, 1.0)


class RunwayFields:
    """Low-frequency fields over the whole runway (stains, rubber, wear), sampled seamlessly per tile."""

    def __init__(self, runway: Runway, layout: MarkingLayout, rng: np.random.Generator):
        self.runway = runway
        self.step_x = 1.0
        self.step_y = 0.25
        nx = int(math.ceil(runway.length_m / self.step_x)) + 3
        ny = int(math.ceil(runway.width_m / self.step_y)) + 3
        self.stain = _smooth_noise((ny, nx), rng, beta=2.2)
        self.wear = _smooth_noise((ny, nx), rng, beta=1.6)
        # rubber: streaks along x (fine across, coarse along) in the touchdown zones of both ends
        across = _smooth_noise((ny, 1), rng, beta=0.8)
        along = _smooth_noise((1, nx), rng, beta=1.8)
        streaks = np.clip(0.55 + 0.45 * across, 0, None) * np.clip(0.7 + 0.3 * along, 0, None)
        x = (np.arange(nx) - 1) * self.step_x
        y = (np.arange(ny) - 1) * self.step_y - runway.width_m / 2.0
        zone_end = max(layout.touchdown_zone_end_m, layout.aiming_point_start_m + 200.0)

        def envelope_x(d):
            return np.clip((d - 60.0) / 120.0, 0, 1) * np.clip((zone_end + 250.0 - d) / 300.0, 0, 1)

        ex = np.maximum(envelope_x(x), envelope_x(runway.length_m - x))
        # main gear tracks: a band of +-(2..8) m about the centre line
        ey = np.exp(-0.5 * ((np.abs(y) - 4.0) / 2.6) ** 2) + 0.6 * np.exp(-0.5 * (y / 1.5) ** 2)
        self.rubber = (streaks * ey[:, None] * ex[None, :]).astype(np.float32)

    def sample(self, field: np.ndarray, x_m, y_m) -> np.ndarray:
        """Bilinear samples of ``field`` at the grid ``y_m (rows) x x_m (cols)``, (len(y_m), len(x_m)) float32."""
        import cv2
        cols = (np.asarray(x_m) / self.step_x + 1.0).astype(np.float32)
        rows = ((np.asarray(y_m) + self.runway.width_m / 2.0) / self.step_y + 1.0).astype(np.float32)
        map_x = np.broadcast_to(cols[None, :], (len(rows), len(cols))).copy()
        map_y = np.broadcast_to(rows[:, None], (len(rows), len(cols))).copy()
        return cv2.remap(field, map_x, map_y, interpolation=cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)


def _smooth_noise(shape, rng, beta):
    rows, cols = shape
    pad_r = max(rows, 8)
    pad_c = max(cols, 8)
    field = tileable_noise((pad_r, pad_c), rng, beta=beta)
    return np.ascontiguousarray(field[:rows, :cols], dtype=np.float32)


def runway_patches(runway: Runway, rng: np.random.Generator, x_from_m: float = 0.0) -> np.ndarray:
    """Repair patches of a ``patched`` runway: rows ``x0, x1, y0, y1, tone`` (tone multiplies the pavement).

    About one patch per 60 m, 6-80 m long, a lane of the runway or its full width, darker
    (fresh asphalt) or lighter (concrete slabs); some start right at the threshold.

    Parameters
    ----------
    runway : visland.runway.Runway
        Its length and width.
    rng : numpy.random.Generator
        Seeded generator of the patches.
    x_from_m : float, default 0
        Patches start at or after this distance past the threshold, metres.

    Returns
    -------
    ndarray, shape (k, 5)
        ``x0, x1, y0, y1`` (metres in R) and ``tone`` of each patch.
    """
    L, W = runway.length_m, runway.width_m
    n = max(4, int((L - x_from_m) / 60.0))
    out = []
    for _ in range(n):
        length = rng.uniform(6.0, 80.0)
        x0 = rng.uniform(x_from_m, L - length)
        if rng.random() < 0.35:
            y0, y1 = -W / 2, W / 2
        else:
            w = rng.uniform(3.0, W / 2)
            y0 = rng.uniform(-W / 2, W / 2 - w)
            y1 = y0 + w
        tone = rng.uniform(0.55, 0.8) if rng.random() < 0.6 else rng.uniform(1.35, 1.9)
        out.append((x0, x0 + length, y0, y1, tone))
    if x_from_m <= 0.0:
        # a patch across the threshold (its edge is not the runway's)
        out.append((0.0, rng.uniform(8.0, 40.0), -W / 2, W / 2, rng.uniform(0.6, 0.8)))
    return np.array(out, dtype=float)


def _paint(colour, coverage, paint_name, wear_alpha=1.0):
    alpha = (coverage * wear_alpha).astype(np.float32)
    paint = np.array(SURFACE_COLOURS[paint_name], dtype=np.float32)
    return colour * (1 - alpha[..., None]) + paint * alpha[..., None]


def pre_threshold_tile(x0_m: float, x1_m: float, runway: Runway, layout: MarkingLayout, surface: str, tone: float,
                       texel_m: float, rng: np.random.Generator) -> np.ndarray:
    """Pavement before the threshold (``x0_m < x1_m <= 0``) with its arrows or chevrons, (rows, cols, 3).

    Same orientation as :func:`runway_tile`; ``tone`` multiplies the pavement colour (a blast pad
    is often of another, older surface).

    Parameters
    ----------
    x0_m, x1_m : float
        The tile's extent, metres in R (``x0_m < x1_m <= 0``).
    runway : visland.runway.Runway
        Its width.
    layout : MarkingLayout
        Its ``polygons`` (arrows or chevrons).
    surface : str
        The pavement (``asphalt``, ``concrete``, ``patched``).
    tone : float
        Multiplies the pavement colour.
    texel_m : float
        Texel size, metres.
    rng : numpy.random.Generator
        Seeded generator of the grain.

    Returns
    -------
    ndarray, shape (rows, cols, 3), uint8
        The pavement, arrows and chevrons painted.
    """
    W = runway.width_m
    cols = max(2, int(math.ceil((x1_m - x0_m) / texel_m)))
    rows = max(2, int(math.ceil(W / texel_m)))
    x_edges = np.linspace(x0_m, x1_m, cols + 1)
    y_edges = np.linspace(-W / 2.0, W / 2.0, rows + 1)
    base = np.array(SURFACE_COLOURS["concrete" if surface == "concrete" else "asphalt"], dtype=np.float32) * tone
    noise = tileable_noise((rows, cols), rng, beta=2.4).astype(np.float32)
    colour = base[None, None, :] * (1.0 + np.float32(0.06) * noise)[..., None]
    for paint_name in ("paint_white", "paint_yellow"):
        polys = [p for c, p in layout.polygons if c == paint_name]
        if polys:
            colour = _paint(colour, coverage_of_polygons(polys, x_edges, y_edges), paint_name, 0.9)
    return _to_uint8(colour)


def runway_tile(x0_m: float, x1_m: float, runway: Runway, layout: MarkingLayout, fields: RunwayFields,
                surface: str, wear: float, rubber: float, texel_m: float, rng: np.random.Generator,
                flat: bool = False, patches=None) -> np.ndarray:
    """The runway between ``x0_m`` and ``x1_m``, full width, with its markings, (rows, cols, 3).

    Columns run along x from ``x0_m`` (texel edges evenly spaced), rows along y from the left
    edge ``-W/2`` (row index increases with y and with the texture coordinate t).
    ``flat`` gives plain white pavement and no markings (label checks).

    Parameters
    ----------
    x0_m, x1_m : float
        The tile's extent along the runway, metres in R.
    runway : visland.runway.Runway
        Its width.
    layout : MarkingLayout
        The markings to paint.
    fields : RunwayFields
        Stains, rubber and wear over the whole runway (sampled seamlessly per tile).
    surface : str
        ``asphalt``, ``concrete`` or ``patched``.
    wear, rubber : float
        Marking wear and rubber deposits, 0 to 1.
    texel_m : float
        Texel size, metres.
    rng : numpy.random.Generator
        Seeded generator of the grain.
    flat : bool, default False
        Plain white pavement, no markings.
    patches : ndarray, shape (k, 5), optional
        Repair patches (:func:`runway_patches`).

    Returns
    -------
    ndarray, shape (rows, cols, 3), uint8
    """
    W = runway.width_m
    cols = max(2, int(math.ceil((x1_m - x0_m) / texel_m)))
    rows = max(2, int(math.ceil(W / texel_m)))
    if flat:
        return np.full((rows, cols, 3), 255, dtype=np.uint8)
    x_edges = np.linspace(x0_m, x1_m, cols + 1)
    y_edges = np.linspace(-W / 2.0, W / 2.0, rows + 1)
    xc = 0.5 * (x_edges[:-1] + x_edges[1:])
    yc = 0.5 * (y_edges[:-1] + y_edges[1:])
    base = np.array(SURFACE_COLOURS["asphalt" if surface == "patched" else surface], dtype=np.float32)
    stain = fields.sample(fields.stain, xc, yc)
    colour = base[None, None, :] * (1.0 + np.float32(0.07) * stain)[..., None]
    if patches is not None:
        for px0, px1, py0, py1, tone in np.asarray(patches, dtype=float).reshape(-1, 5):
            if px1 <= x0_m or px0 >= x1_m:
                continue
            cover = coverage_of_rectangles(np.array([[px0, px1, py0, py1]]), x_edges, y_edges).astype(np.float32)
            colour = colour * (1.0 + np.float32(tone - 1.0) * cover)[..., None]
    if surface == "concrete":
        # slab joints every 7.5 m across and along (darker lines one texel wide)
        jx = np.abs(((xc + 3.75) % 7.5) - 3.75) < texel_m / 2
        jy = np.abs(((yc + 3.75) % 7.5) - 3.75) < texel_m / 2
        colour[:, jx] *= 0.8
        colour[jy, :] *= 0.8
    paint = coverage_of_rectangles(layout.rectangles_m, x_edges, y_edges)
    if paint.any():
        wear_field = fields.sample(fields.wear, xc, yc)
        rubber_field = fields.sample(fields.rubber, xc, yc)
        worn = np.clip(np.float32(wear) * (0.55 + 0.45 * wear_field + 0.8 * rubber_field), 0.0, 0.95)
        alpha = (paint * (1.0 - worn)).astype(np.float32)
        white = np.array(SURFACE_COLOURS["paint_white"], dtype=np.float32)
        colour = colour * (1 - alpha[..., None]) + white * alpha[..., None]
    if rubber > 0:
        r = np.clip(fields.sample(fields.rubber, xc, yc) * np.float32(rubber * 0.85), 0, 0.9)
        black = np.array(SURFACE_COLOURS["rubber"], dtype=np.float32)
        colour = colour * (1 - r[..., None]) + black * r[..., None]
    return _to_uint8(colour)


def strip_texture(kind: str, width_m: float, rng: np.random.Generator, texel_m: float = 0.08,
                  period_m: float = 12.0, flat: bool = False) -> np.ndarray:
    """One period of a taxiway or road strip, (rows across the width, cols along the length, 3).

    ``kind``: ``"taxiway"`` (asphalt, yellow centre line 0.15 m), ``"road"`` (asphalt, white
    edge lines and a 3 m / 9 m dashed centre line) or ``"runway"`` (a second runway: concrete,
    side stripes, dashed centre line). Rows span the width from one edge to the
    other, columns one ``period_m`` along the strip (the texture repeats along it).

    Parameters
    ----------
    kind : str
        ``"taxiway"``, ``"road"`` or ``"runway"``.
    width_m : float
        The strip's width, metres.
    rng : numpy.random.Generator
        Seeded generator of the grain.
    texel_m : float, default 0.08
        Texel size, metres.
    period_m : float, default 12
        Length of one period, metres.
    flat : bool, default False
        Plain colours (label checks).

    Returns
    -------
    ndarray, shape (rows, cols, 3), uint8
    """
    rows = max(4, int(math.ceil(width_m / texel_m)))
    cols = max(4, int(math.ceil(period_m / texel_m)))
    if kind not in ("taxiway", "road", "runway"):
        raise ValueError(f"kind must be 'taxiway', 'road' or 'runway', got {kind!r}")
    if flat:
        return np.full((rows, cols, 3), 60, dtype=np.uint8)
    base = np.array(SURFACE_COLOURS[{"taxiway": "taxiway_asphalt", "road": "road_asphalt",
                                     "runway": "concrete"}[kind]])
    colour = base[None, None, :] * (1.0 + 0.03 * rng.standard_normal((rows, cols)))[..., None]
    x_edges = np.linspace(0.0, period_m, cols + 1)
    y_edges = np.linspace(-width_m / 2, width_m / 2, rows + 1)
    if kind == "taxiway":
        rects = [(0.0, period_m, -0.075, 0.075)]
        paint_colour = SURFACE_COLOURS["paint_yellow"]
    elif kind == "runway":
        # a second runway seen from the side: centre line 30 m of every period, side stripes
        rects = [(0.0, min(30.0, 0.6 * period_m), -0.45, 0.45), (0.0, period_m, -width_m / 2, -width_m / 2 + 0.9),
                 (0.0, period_m, width_m / 2 - 0.9, width_m / 2)]
        paint_colour = SURFACE_COLOURS["paint_white"]
    else:
        rects = [(0.0, 3.0, -0.06, 0.06), (0.0, period_m, -width_m / 2 + 0.3, -width_m / 2 + 0.45),
                 (0.0, period_m, width_m / 2 - 0.45, width_m / 2 - 0.3)]
        paint_colour = SURFACE_COLOURS["paint_white"]
    alpha = coverage_of_rectangles(np.array(rects), x_edges, y_edges) * 0.85
    colour = colour * (1 - alpha[..., None]) + np.array(paint_colour) * alpha[..., None]
    return _to_uint8(colour)
