"""The airport scene: trimesh geometry in the runway frame, turned into a pyrender Scene.

Layout (runway frame R, metres; W, L the runway's width and length):

- the runway ``[0, L] x [-W/2, W/2]``, cut in tiles about 50 m long, each with its own
  texture holding the painted markings (:mod:`visland.render.markings`);
- a parallel taxiway on the right at ``4 W + 2.5`` m from the centre line (182.5 m for a 45 m
  runway, ICAO code E) joined to the runway by three connectors (none near the threshold, so
  the threshold corners stay clean), an apron and buildings beyond it;
- with ``taxiways="oblique"``: a parallel taxiway on each side, joined to the runway by taxiways
  at an angle (rapid exits at 45 deg within 200 m of the threshold and at 30 deg at 0.4 L on
  the right, at 35 deg 120 m past the threshold on the left; :class:`ObliqueStrip`);
- two roads (one parallel on the left, one crossing 1.4 km before the threshold);
- fields and woods around mown airport grass out to 60 km; a sky dome that follows the camera.

Depth precision: every ground surface lies in the plane z = 0 and **no two surfaces overlap**.
The ground is one tensor grid whose lines pass through every edge of every paved area; each
cell belongs to exactly one surface and neighbouring cells share their vertices, so there is
nothing to z-fight and no crack at any distance. A taxiway at an angle is cut out of the ground
cells it crosses (:func:`_split_cell`): its corners are grid points, its two ends lie on grid
lines (the runway's and the parallel taxiway's edges), and where a slanted side crosses a grid
line both cells on that line get the same vertex, computed from the side and the line alone, so
the no-crack rule holds there too. Markings are painted into the runway textures, not stacked
as geometry. Only buildings and the sky use depth, far apart.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from visland.runway import Runway

from .markings import runway_markings
from .params import SceneParams
from . import textures

__all__ = ["AirportLayout", "ObliqueStrip", "airport_layout", "build_scene", "SceneHandles", "GROUND_EXTENT_M",
           "SKY_RADIUS_M"]

GROUND_EXTENT_M = 60000.0
SKY_RADIUS_M = 120000.0
RUNWAY_TILE_M = 50.0
_CLAMP = 33071       # GL_CLAMP_TO_EDGE
#: Surface kinds of the shaders (see visland.render.shaders).
_KIND_NAMES = {0: "KIND_GROUND", 1: "KIND_SKY", 2: "KIND_BUILDING", 3: "KIND_FLAT", 4: "KIND_PAVEMENT"}
_REPEAT = 10497      # GL_REPEAT


@dataclass(frozen=True)
class Region:
    """An axis-aligned paved area: ``rect = (x0, x1, y0, y1)``; strips repeat a texture along ``axis``."""

    name: str
    rect: tuple
    material: str
    priority: int
    axis: str = "x"           # direction along which a strip texture runs
    width_m: float = 0.0      # strip width (across the axis)


@dataclass(frozen=True)
class ObliqueStrip:
    """A taxiway joining the runway at an angle: a parallelogram whose two ends lie on lines of
    constant y (the runway's edge and the parallel taxiway's), runway frame R, metres.

    Attributes
    ----------
    name : str
        For the layout's listing.
    corners : tuple
        Four ``(x, y)``: the runway end's two corners, then the far end's, in the order
        ``(near_a, near_b, far_b, far_a)`` (``a`` on the side of smaller x).
    width_m : float
        Width across the strip.
    material : str, default "taxiway"
        Strip texture (:func:`visland.render.textures.strip_texture`).
    """

    name: str
    corners: tuple
    width_m: float
    material: str = "taxiway"

    @classmethod
    def joining(cls, name: str, x_join_m: float, side: int, angle_deg: float, y_near_m: float, y_far_m: float,
                width_m: float) -> "ObliqueStrip":
        """The strip leaving the line ``y = y_near_m`` at ``x_join_m`` (centre of its mouth) at
        ``angle_deg`` from the runway's axis towards +x, until ``y = y_far_m``; ``side`` is the sign
        of y (+1 right, -1 left), ``y_*`` are distances from the centre line (positive)."""
        angle = math.radians(angle_deg)
        half_mouth = 0.5 * width_m / math.sin(angle)                 # the mouth cut along y = const
        run = (y_far_m - y_near_m) / math.tan(angle)                 # x travelled from one end to the other
        near_y, far_y = side * y_near_m, side * y_far_m
        corners = ((x_join_m - half_mouth, near_y), (x_join_m + half_mouth, near_y),
                   (x_join_m + run + half_mouth, far_y), (x_join_m + run - half_mouth, far_y))
        return cls(name, corners, float(width_m))

    def axis_and_normal(self) -> tuple[np.ndarray, np.ndarray]:
        """Unit vectors along the strip (from the runway outwards) and across it, (2,) each."""
        c = np.asarray(self.corners, dtype=float)
        along = 0.5 * (c[2] + c[3]) - 0.5 * (c[0] + c[1])
        along /= np.linalg.norm(along)
        return along, np.array([-along[1], along[0]])


@dataclass(frozen=True)
class AirportLayout:
    """Paved regions (highest priority wins a grid cell) and buildings, in the runway frame R.

    Attributes
    ----------
    regions : tuple of Region
        Runway, taxiways, apron, roads: ``rect = (x0, x1, y0, y1)`` in metres.
    buildings : tuple
        ``(x0, x1, y0, y1, height, rgb)`` each, metres.
    grass_rect : tuple
        ``(x0, x1, y0, y1)`` of the mown airport grass, metres.
    runway_tile_edges_m : ndarray, shape (n_tiles + 1,)
        Where the runway's texture tiles start and end along x, metres.
    oblique : tuple of ObliqueStrip, default ()
        Taxiways at an angle, cut out of the ground.
    """

    regions: tuple
    buildings: tuple
    grass_rect: tuple
    runway_tile_edges_m: np.ndarray
    oblique: tuple = ()


def airport_layout(runway: Runway, distractors: bool = True, taxiways: str = "standard", second_runway: bool = False,
                   pre_threshold_m: float = 0.0) -> AirportLayout:
    """Where everything is, in the runway frame (see module docstring).

    ``taxiways`` (``SceneParams.taxiways``): ``near_threshold`` adds a parallel taxiway on the
    left and connectors at 90 m (right) and 230 m (left) past the threshold; ``none`` draws no
    taxiway, apron or building (roads stay). ``second_runway`` adds a parallel runway 400 m to
    the left, its threshold 600 m before ours. ``pre_threshold_m`` > 0 paves ``[-pre, 0]`` at
    the runway's width (displaced threshold or blast pad).

    Parameters
    ----------
    runway : visland.runway.Runway
        Its length and width.
    distractors : bool, default True
        Taxiways, apron, buildings and roads around the runway (False: the runway alone).
    taxiways : str, default "standard"
        ``standard``, ``near_threshold``, ``oblique`` or ``none``.
    second_runway : bool, default False
        Add the parallel runway.
    pre_threshold_m : float, default 0
        Paved length before the threshold, metres.

    Returns
    -------
    AirportLayout
    """
    L, W = runway.length_m, runway.width_m
    n_tiles = max(1, int(math.ceil(L / RUNWAY_TILE_M)))
    tile_edges = np.linspace(0.0, L, n_tiles + 1)
    regions = [Region("runway", (0.0, L, -W / 2, W / 2), "runway", 100)]
    if pre_threshold_m > 0:
        regions.append(Region("pre_threshold", (-pre_threshold_m, 0.0, -W / 2, W / 2), "pre_threshold", 90))
    buildings = []
    grass_x0 = -450.0 - pre_threshold_m
    grass_y0 = -330.0
    if distractors and second_runway:
        w2 = max(30.0, 0.8 * W)
        y2 = -(W / 2 + 400.0)
        regions.append(Region("second_runway", (-600.0, max(L - 900.0, 600.0), y2 - w2 / 2, y2 + w2 / 2), "runway2",
                              60, "x", w2))
        grass_y0 = y2 - w2 / 2 - 120.0
        grass_x0 = min(grass_x0, -750.0)
    if distractors and taxiways == "none":
        road_w = 8.0
        regions.append(Region("road_parallel", (-GROUND_EXTENT_M, GROUND_EXTENT_M, -650.0 - road_w / 2 + min(0.0, grass_y0 + 330.0),
                                                -650.0 + road_w / 2 + min(0.0, grass_y0 + 330.0)), "road", 20, "x", road_w))
        return AirportLayout(tuple(regions), (), (grass_x0, L + 450.0, grass_y0, 330.0), tile_edges)
    oblique = []
    if distractors:
        if taxiways in ("near_threshold", "oblique"):
            sep = 4.0 * W + 2.5
            tw = min(23.0, 0.5 * W + 0.5)
            regions.append(Region("left_parallel_taxiway", (60.0, L - 40.0, -sep - tw / 2, -sep + tw / 2), "taxiway",
                                  50, "x", tw))
            if taxiways == "near_threshold":
                regions.append(Region("connector_near_right", (90.0 - tw / 2, 90.0 + tw / 2, W / 2, sep - tw / 2),
                                      "taxiway", 40, "y", tw))
                regions.append(Region("connector_near_left", (230.0 - tw / 2, 230.0 + tw / 2, -sep + tw / 2, -W / 2),
                                      "taxiway", 40, "y", tw))
            regions.append(Region("connector_far_left", (L - 60.0 - tw / 2, L - 60.0 + tw / 2, -sep + tw / 2, -W / 2),
                                  "taxiway", 40, "y", tw))
        sep = 4.0 * W + 2.5
        tw = min(23.0, 0.5 * W + 0.5)
        t_in, t_out = sep - tw / 2, sep + tw / 2
        regions.append(Region("parallel_taxiway", (60.0, L - 40.0, t_in, t_out), "taxiway", 50, "x", tw))
        if taxiways == "oblique":
            # rapid exits instead of the two first right-angle connectors; they end on the
            # parallel taxiways' inner edges, so each crosses nothing but ground
            oblique = [ObliqueStrip.joining("oblique_near_right", min(200.0, 0.15 * L), +1, 45.0, W / 2, t_in, tw),
                       ObliqueStrip.joining("oblique_exit_right", 0.4 * L, +1, 30.0, W / 2, t_in, tw),
                       ObliqueStrip.joining("oblique_near_left", min(120.0, 0.1 * L), -1, 35.0, W / 2, t_in, tw)]
            connectors = (L - 60.0,)
        else:
            connectors = (0.28 * L, 0.52 * L, L - 60.0)
        for k, x_c in enumerate(connectors):
            regions.append(Region(f"connector_{k}", (x_c - tw / 2, x_c + tw / 2, W / 2, t_in), "taxiway", 40, "y", tw))
        a_x0, a_x1 = 0.36 * L, 0.60 * L
        a_y0, a_y1 = t_out + 45.0, t_out + 245.0
        regions.append(Region("apron_link", (0.48 * L - tw / 2, 0.48 * L + tw / 2, t_out, a_y0), "taxiway", 40, "y", tw))
        regions.append(Region("apron", (a_x0, a_x1, a_y0, a_y1), "apron", 30))
        road_w = 8.0
        y_road = -650.0 + min(0.0, grass_y0 + 330.0)
        regions.append(Region("road_parallel", (-GROUND_EXTENT_M, GROUND_EXTENT_M, y_road - road_w / 2,
                                                y_road + road_w / 2), "road", 20, "x", road_w))
        regions.append(Region("road_crossing", (-1400.0 - road_w / 2, -1400.0 + road_w / 2, -GROUND_EXTENT_M,
                                                GROUND_EXTENT_M), "road", 10, "y", road_w))
        # terminal, hangars, tower, cargo sheds beyond the apron; farms along the road
        terminal_y = a_y1 + 20.0
        buildings += [
            (a_x0 + 30.0, a_x0 + 0.55 * (a_x1 - a_x0), terminal_y, terminal_y + 45.0, 16.0, (0.78, 0.78, 0.76)),
            (a_x0 + 0.62 * (a_x1 - a_x0), a_x0 + 0.62 * (a_x1 - a_x0) + 85.0, terminal_y, terminal_y + 70.0, 22.0,
             (0.70, 0.74, 0.78)),
            (a_x1 - 70.0, a_x1, terminal_y, terminal_y + 60.0, 20.0, (0.86, 0.86, 0.84)),
            (a_x0 - 60.0, a_x0 - 48.0, a_y0 + 20.0, a_y0 + 32.0, 38.0, (0.82, 0.80, 0.76)),
            (a_x1 + 60.0, a_x1 + 150.0, a_y0, a_y0 + 40.0, 11.0, (0.60, 0.42, 0.36)),
        ]
        for x_farm, y_farm in ((-2600.0, -720.0), (-900.0, -700.0), (900.0, -710.0), (-3300.0, 900.0),
                               (L + 1500.0, -720.0)):
            buildings.append((x_farm, x_farm + 30.0, y_farm - 14.0, y_farm, 8.0, (0.64, 0.44, 0.36)))
            buildings.append((x_farm + 40.0, x_farm + 75.0, y_farm - 20.0, y_farm - 2.0, 7.0, (0.72, 0.72, 0.70)))
        grass_rect = (grass_x0, L + 450.0, grass_y0, a_y1 + 140.0)
    else:
        grass_rect = (grass_x0, L + 450.0, grass_y0, 330.0)
    return AirportLayout(tuple(regions), tuple(buildings), grass_rect, tile_edges, tuple(oblique))


@dataclass
class SceneHandles:
    """The pyrender scene and the node that must follow the camera.

    Attributes
    ----------
    scene : pyrender.Scene
        The airport, in the runway frame R.
    sky_node : pyrender.Node
        The sky dome, moved to the camera at each frame.
    max_structure_height_m : float
        Height of the tallest building, metres (for the clipping planes).
    """

    scene: object
    sky_node: object
    max_structure_height_m: float


def _texture(image_t_rows, wrap: int, trilinear: bool = True):
    """A pyrender texture from an image whose row index grows with t (see :func:`glview.make_texture`)."""
    from .glview import make_texture
    return make_texture(image_t_rows, wrap, trilinear)


def _material(base_texture=None, detail_texture=None, detail_per_m=0.0, detail_strength=0.0, kind=0,
              colour=(1.0, 1.0, 1.0)):
    import pyrender
    return pyrender.MetallicRoughnessMaterial(
        name=_KIND_NAMES[kind], baseColorFactor=(*colour, 1.0), baseColorTexture=base_texture,
        emissiveTexture=detail_texture, emissiveFactor=(detail_per_m, detail_strength, float(kind)),
        metallicFactor=0.0, roughnessFactor=1.0, doubleSided=True)


def _grid_edges(layout: AirportLayout) -> tuple[np.ndarray, np.ndarray]:
    xs = {-GROUND_EXTENT_M, GROUND_EXTENT_M}
    ys = {-GROUND_EXTENT_M, GROUND_EXTENT_M}
    for region in layout.regions:
        x0, x1, y0, y1 = region.rect
        xs |= {x0, x1}
        ys |= {y0, y1}
    for strip in layout.oblique:
        xs |= {float(x) for x, _ in strip.corners}
        ys |= {float(y) for _, y in strip.corners}
    xs |= set(layout.runway_tile_edges_m.tolist())
    # a ring of breakpoints keeps the large ground triangles moderate near the airport
    for r in (1000.0, 2500.0, 5000.0, 10000.0, 20000.0, 40000.0):
        xs |= {-r, layout.runway_tile_edges_m[-1] + r}
        ys |= {-r, r}
    xs = np.array(sorted(v for v in xs if -GROUND_EXTENT_M <= v <= GROUND_EXTENT_M))
    ys = np.array(sorted(v for v in ys if -GROUND_EXTENT_M <= v <= GROUND_EXTENT_M))
    return xs, ys


def _cell_owners(layout: AirportLayout, xs, ys) -> np.ndarray:
    """Index of the region owning each grid cell (-1: ground), shape (len(ys)-1, len(xs)-1)."""
    xc = 0.5 * (xs[:-1] + xs[1:])
    yc = 0.5 * (ys[:-1] + ys[1:])
    owner = np.full((len(yc), len(xc)), -1)
    best = np.full(owner.shape, -np.inf)
    for k, region in enumerate(layout.regions):
        x0, x1, y0, y1 = region.rect
        inside = ((yc[:, None] > y0) & (yc[:, None] < y1)) & ((xc[None, :] > x0) & (xc[None, :] < x1))
        take = inside & (region.priority > best)
        owner[take] = k
        best[take] = region.priority
    return owner


def _quads_mesh(cells, uv_of):
    """trimesh of axis-aligned cells ``(x0, x1, y0, y1)`` at z = 0 with UVs ``uv_of(x, y) -> (s, t)``."""
    import trimesh
    cells = np.asarray(cells, dtype=float).reshape(-1, 4)
    x0, x1, y0, y1 = cells.T
    vx = np.stack([x0, x1, x1, x0], axis=1).ravel()
    vy = np.stack([y0, y0, y1, y1], axis=1).ravel()
    vertices = np.stack([vx, vy, np.zeros_like(vx)], axis=1)
    base = np.arange(len(cells))[:, None] * 4
    # counter-clockwise seen from above (from -z): normal points up (-z)
    faces = np.concatenate([base + np.array([0, 2, 1]), base + np.array([0, 3, 2])], axis=0)
    visual = None
    if uv_of is not None:
        visual = trimesh.visual.TextureVisuals(uv=np.stack(uv_of(vx, vy), axis=1))
    return trimesh.Trimesh(vertices=vertices, faces=faces, visual=visual, process=False)


def _crossing(a, b, p, q):
    """Where the segment ``a``-``b`` meets the line through ``p`` and ``q`` (2-D points). A segment
    along a grid line (x or y constant) gets the point computed from the line and that grid
    coordinate alone, so the two cells that share the grid line get the same vertex (no crack)."""
    if a[0] == b[0]:
        return (a[0], p[1] + (a[0] - p[0]) * (q[1] - p[1]) / (q[0] - p[0]))
    if a[1] == b[1]:
        return (p[0] + (a[1] - p[1]) * (q[0] - p[0]) / (q[1] - p[1]), a[1])
    d = (b[0] - a[0], b[1] - a[1])
    e = (q[0] - p[0], q[1] - p[1])
    t = ((p[0] - a[0]) * e[1] - (p[1] - a[1]) * e[0]) / (d[0] * e[1] - d[1] * e[0])
    return (a[0] + t * d[0], a[1] + t * d[1])


def _clip(polygon, p, q, sign: float):
    """The part of the convex ``polygon`` (list of (x, y)) where ``sign * cross(q - p, v - p) >= 0``."""
    def side(v):
        return sign * ((q[0] - p[0]) * (v[1] - p[1]) - (q[1] - p[1]) * (v[0] - p[0]))
    out = []
    for k, a in enumerate(polygon):
        b = polygon[(k + 1) % len(polygon)]
        sa, sb = side(a), side(b)
        if sa >= 0:
            out.append(a)
        if (sa > 0 > sb) or (sa < 0 < sb):
            out.append(_crossing(a, b, p, q))
    return out


def _signed_area(ring) -> float:
    """Shoelace area of a polygon (list of (x, y)): positive when counter-clockwise in (x, y)."""
    ring = list(ring)
    return 0.5 * sum(a[0] * b[1] - b[0] * a[1] for a, b in zip(ring, ring[1:] + ring[:1]))


def _split_cell(polygon, strip: ObliqueStrip) -> tuple[list, list]:
    """``(inside, outside)`` convex pieces of the convex ground ``polygon`` cut by ``strip``'s two
    slanted sides (its ends lie on grid lines, so a grid cell is wholly inside or outside their
    band). Pieces of no area are dropped."""
    c = strip.corners
    centre = tuple(np.mean(np.asarray(c, dtype=float), axis=0))
    sides = [(c[0], c[3]), (c[1], c[2])]
    signs = []
    for p, q in sides:
        value = (q[0] - p[0]) * (centre[1] - p[1]) - (q[1] - p[1]) * (centre[0] - p[0])
        signs.append(1.0 if value > 0 else -1.0)
    (pa, qa), (pb, qb) = sides
    outside = [_clip(polygon, pa, qa, -signs[0])]
    between = _clip(polygon, pa, qa, signs[0])
    outside.append(_clip(between, pb, qb, -signs[1]))
    inside = _clip(between, pb, qb, signs[1])
    keep = [piece for piece in outside if len(piece) >= 3 and abs(_signed_area(piece)) > 1e-6]
    return ([inside] if len(inside) >= 3 and abs(_signed_area(inside)) > 1e-6 else []), keep


def _polygons_mesh(polygons, uv_of):
    """trimesh of convex polygons at z = 0 (fans), UVs ``uv_of(x, y) -> (s, t)``; the same winding
    as :func:`_quads_mesh` (normal up, -z)."""
    import trimesh
    vertices, faces = [], []
    for polygon in polygons:
        base = len(vertices)
        ring = list(polygon)
        if _signed_area(ring) < 0:
            ring = ring[::-1]
        vertices.extend(ring)
        faces.extend([base, base + k + 1, base + k] for k in range(1, len(ring) - 1))
    v = np.asarray(vertices, dtype=float).reshape(-1, 2)
    vertices3 = np.column_stack([v, np.zeros(len(v))])
    visual = None
    if uv_of is not None:
        visual = trimesh.visual.TextureVisuals(uv=np.stack(uv_of(v[:, 0], v[:, 1]), axis=1))
    return trimesh.Trimesh(vertices=vertices3, faces=np.asarray(faces, dtype=int).reshape(-1, 3), visual=visual,
                           process=False)


def _ground_and_oblique(ground_cells, layout: AirportLayout):
    """The ground cells untouched by the oblique strips, the ground pieces they leave, and the
    strips' own pieces by strip: ``(cells, ground_polygons, {strip index: polygons})``."""
    if not layout.oblique:
        return ground_cells, [], {}
    keep = np.ones(len(ground_cells), dtype=bool)
    ground_polygons, strip_polygons = [], {}
    for k, strip in enumerate(layout.oblique):
        c = np.asarray(strip.corners, dtype=float)
        x0, x1, y0, y1 = c[:, 0].min(), c[:, 0].max(), c[:, 1].min(), c[:, 1].max()
        hit = keep & (ground_cells[:, 0] < x1) & (ground_cells[:, 1] > x0) & (ground_cells[:, 2] < y1) \
            & (ground_cells[:, 3] > y0)
        pieces = [[(a, c_), (b, c_), (b, d), (a, d)] for a, b, c_, d in ground_cells[hit]]
        keep &= ~hit
        # pieces other strips left behind may lie in this strip's band too
        overlapping = [_bbox_overlaps(g, x0, x1, y0, y1) for g in ground_polygons]
        pieces += [g for g, hit_g in zip(ground_polygons, overlapping) if hit_g]
        ground_polygons = [g for g, hit_g in zip(ground_polygons, overlapping) if not hit_g]
        for piece in pieces:
            inside, outside = _split_cell(piece, strip)
            strip_polygons.setdefault(k, []).extend(inside)
            ground_polygons.extend(outside)
    return ground_cells[keep], ground_polygons, strip_polygons


def _bbox_overlaps(polygon, x0, x1, y0, y1) -> bool:
    xs = [v[0] for v in polygon]
    ys = [v[1] for v in polygon]
    return min(xs) < x1 and max(xs) > x0 and min(ys) < y1 and max(ys) > y0


def _add(scene, mesh):
    """Add ``mesh`` under a name recording the order of addition (the renderer draws in name order)."""
    return scene.add(mesh, name=f"{len(scene.mesh_nodes):04d}")


def build_scene(runway: Runway, params: SceneParams) -> SceneHandles:
    """Build the airport scene of ``runway`` as a pyrender Scene in the runway frame.

    Textures are generated from ``params.seed`` (same seed, same scene, in every process).

    Parameters
    ----------
    runway : visland.runway.Runway
        The runway (size; markings from ``params``).
    params : SceneParams
        How the scene looks.

    Returns
    -------
    SceneHandles
    """
    import pyrender
    import trimesh

    flat = params.style == "flat"
    marking_layout = runway_markings(runway, params.markings, params.threshold_stripes, params.side_stripes,
                                     params.pre_threshold_m)
    pre = 0.0 if flat else marking_layout.pre_threshold_m
    layout = airport_layout(runway, distractors=params.distractors and not flat, taxiways=params.taxiways,
                            second_runway=params.second_runway, pre_threshold_m=pre)
    wear = max(params.marking_wear, 0.85) if params.markings == "worn" else params.marking_wear
    scene = pyrender.Scene(bg_color=(0.0, 0.0, 0.0, 1.0), ambient_light=(0.0, 0.0, 0.0))

    xs, ys = _grid_edges(layout)
    owner = _cell_owners(layout, xs, ys)
    rows, cols = np.nonzero(np.ones_like(owner, dtype=bool))
    all_cells = np.stack([xs[cols], xs[cols + 1], ys[rows], ys[rows + 1]], axis=1)
    owners = owner[rows, cols]

    # ------------------------------------------------------------ ground (fields and grass)
    ground_cells, ground_polygons, oblique_polygons = _ground_and_oblique(all_cells[owners == -1], layout)
    if flat:
        ground_material = _material(kind=3, colour=(0.0, 0.0, 0.0))
        _add(scene, pyrender.Mesh.from_trimesh(_quads_mesh(ground_cells, None), material=ground_material))
    else:
        extent = 12800.0
        centre = (runway.length_m / 2.0, 0.0)
        fields = textures.fields_texture(np.random.default_rng([params.seed, 1]), 1024, extent, centre,
                                         layout.grass_rect, surroundings=params.surroundings)
        grass = textures.grass_detail(np.random.default_rng([params.seed, 2]), 1024)

        def ground_uv(x, y):
            return (x - (centre[0] - extent / 2)) / extent, (y - (centre[1] - extent / 2)) / extent

        ground_material = _material(_texture(fields, _REPEAT), _texture(grass, _REPEAT, trilinear=False), 1.0 / 16.0,
                                    0.8)
        ground = _quads_mesh(ground_cells, ground_uv)
        if ground_polygons:
            ground = trimesh.util.concatenate([ground, _polygons_mesh(ground_polygons, ground_uv)])
        _add(scene, pyrender.Mesh.from_trimesh(ground, material=ground_material))

    # ------------------------------------------------------------ runway tiles
    runway_index = [k for k, r in enumerate(layout.regions) if r.material == "runway"][0]
    runway_cells = all_cells[owners == runway_index]
    fields_rw = None if flat else textures.RunwayFields(runway, marking_layout, np.random.default_rng([params.seed, 3]))
    detail_pavement = None
    if not flat:
        joints = 0
        detail_pavement = _texture(textures.pavement_detail(np.random.default_rng([params.seed, 4]), 512, joints),
                                   _REPEAT, trilinear=False)
    edges = layout.runway_tile_edges_m
    centres_x = 0.5 * (runway_cells[:, 0] + runway_cells[:, 1])
    tile_of_cell = np.clip(np.searchsorted(edges, centres_x) - 1, 0, len(edges) - 2)
    W = runway.width_m
    patches = (textures.runway_patches(runway, np.random.default_rng([params.seed, 9]))
               if params.surface == "patched" and not flat else None)
    for tile in range(len(edges) - 1):
        cells = runway_cells[tile_of_cell == tile]
        if not len(cells):
            continue
        x0, x1 = edges[tile], edges[tile + 1]
        image = textures.runway_tile(x0, x1, runway, marking_layout, fields_rw, params.surface, wear,
                                     params.rubber_deposits, params.texel_m,
                                     np.random.default_rng([params.seed, 5, tile]), flat=flat, patches=patches)

        def tile_uv(x, y, x0=x0, x1=x1):
            return (x - x0) / (x1 - x0), (y + W / 2) / W

        if flat:
            material = _material(kind=3, colour=(1.0, 1.0, 1.0))
            _add(scene, pyrender.Mesh.from_trimesh(_quads_mesh(cells, None), material=material))
        else:
            material = _material(_texture(image, _CLAMP), detail_pavement, 1.0 / 8.0, 0.8, kind=4)
            _add(scene, pyrender.Mesh.from_trimesh(_quads_mesh(cells, tile_uv), material=material))

    # ------------------------------------------------------------ pavement before the threshold
    pre_idx = [k for k, r in enumerate(layout.regions) if r.material == "pre_threshold"]
    if pre_idx:
        cells = all_cells[owners == pre_idx[0]]
        x0, x1 = -pre, 0.0
        tone = 1.0 if params.markings == "displaced" else 1.25
        image = textures.pre_threshold_tile(x0, x1, runway, marking_layout, params.surface, tone, params.texel_m,
                                            np.random.default_rng([params.seed, 10]))

        def pre_uv(x, y, x0=x0, x1=x1):
            return (x - x0) / (x1 - x0), (y + W / 2) / W

        material = _material(_texture(image, _CLAMP), detail_pavement, 1.0 / 8.0, 0.8, kind=4)
        _add(scene, pyrender.Mesh.from_trimesh(_quads_mesh(cells, pre_uv), material=material))

    # ------------------------------------------------------------ strips and apron
    strip_textures = {}
    for material_name in ("taxiway", "road", "apron", "runway2"):
        idx = [k for k, r in enumerate(layout.regions) if r.material == material_name]
        if not idx:
            continue
        mask = np.isin(owners, idx)
        cells = all_cells[mask]
        cell_regions = [layout.regions[k] for k in owners[mask]]
        if material_name == "apron":
            apron_detail = textures.pavement_detail(np.random.default_rng([params.seed, 6]), 512, joints_every_px=85)
            colour = np.array(textures.SURFACE_COLOURS["apron_concrete"]) / 255.0
            material = _material(None, _texture(apron_detail, _REPEAT, trilinear=False), 1.0 / 30.0, 0.9,
                                 colour=tuple(colour))
            _add(scene, pyrender.Mesh.from_trimesh(_quads_mesh(cells, None), material=material))
            continue
        period = 50.0 if material_name == "runway2" else 12.0
        width = cell_regions[0].width_m
        if material_name not in strip_textures:
            strip_textures[material_name] = textures.strip_texture(
                "runway" if material_name == "runway2" else material_name, width,
                np.random.default_rng([params.seed, 7, len(strip_textures)]), 0.08, period)
        # per-cell UVs: along the strip axis s = position / period, across t from one edge to the other
        meshes = []
        for cell, region in zip(cells, cell_regions):
            rx0, rx1, ry0, ry1 = region.rect
            if region.axis == "x":
                def uv(x, y, ry0=ry0, ry1=ry1):
                    return x / period, (y - ry0) / (ry1 - ry0)
            else:
                def uv(x, y, rx0=rx0, rx1=rx1):
                    return y / period, (x - rx0) / (rx1 - rx0)
            meshes.append(_quads_mesh(cell[None, :], uv))
        mesh = trimesh.util.concatenate(meshes)
        material = _material(_texture(strip_textures[material_name], _REPEAT), detail_pavement, 1.0 / 8.0, 0.6, kind=4)
        _add(scene, pyrender.Mesh.from_trimesh(mesh, material=material))

    # ------------------------------------------------------------ taxiways at an angle
    for k, polygons in oblique_polygons.items():
        strip = layout.oblique[k]
        along, across = strip.axis_and_normal()
        mouth = 0.5 * (np.asarray(strip.corners[0], dtype=float) + np.asarray(strip.corners[1], dtype=float))
        period = 12.0
        image = textures.strip_texture(strip.material, strip.width_m, np.random.default_rng([params.seed, 11, k]),
                                       0.08, period)

        def oblique_uv(x, y, along=along, across=across, mouth=mouth, width=strip.width_m):
            dx, dy = x - mouth[0], y - mouth[1]
            # the mouth is cut along the runway edge: measure across from the strip's centre line
            return (dx * along[0] + dy * along[1]) / period, (dx * across[0] + dy * across[1]) / width + 0.5

        material = _material(_texture(image, _REPEAT), detail_pavement, 1.0 / 8.0, 0.6, kind=4)
        _add(scene, pyrender.Mesh.from_trimesh(_polygons_mesh(polygons, oblique_uv), material=material))

    # ------------------------------------------------------------ buildings
    max_height = 0.0
    if layout.buildings:
        boxes = []
        for x0, x1, y0, y1, height, rgb in layout.buildings:
            box = trimesh.creation.box(extents=(x1 - x0, y1 - y0, height))
            box.apply_translation(((x0 + x1) / 2, (y0 + y1) / 2, -height / 2))
            box.visual.face_colors = np.array([*rgb, 1.0]) * 255
            boxes.append(box)
            max_height = max(max_height, height)
        mesh = trimesh.util.concatenate(boxes)
        _add(scene, pyrender.Mesh.from_trimesh(mesh, material=_material(kind=2), smooth=False))

    # ------------------------------------------------------------ sky dome (follows the camera)
    dome = trimesh.creation.icosphere(subdivisions=3, radius=SKY_RADIUS_M)
    # the upper half and a band down to 6 deg below the horizon (beyond the ground's edge):
    # the sky shader never runs where the ground hides it
    keep = (dome.vertices[dome.faces][:, :, 2] < SKY_RADIUS_M * math.sin(math.radians(6.0))).any(axis=1)
    dome.update_faces(keep)
    dome.remove_unreferenced_vertices()
    if flat:
        sky_material = _material(kind=3, colour=(0.0, 0.0, 0.0))
    else:
        clouds = textures.cloud_texture(np.random.default_rng([params.seed, 8]), 512)
        sky_material = _material(_texture(clouds, _REPEAT), kind=1)
    sky_node = _add(scene, pyrender.Mesh.from_trimesh(dome, material=sky_material))
    return SceneHandles(scene=scene, sky_node=sky_node, max_structure_height_m=max_height)
