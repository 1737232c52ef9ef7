"""visland's GLSL shaders, written per scene (sun, haze and sky colours are compiled in).

pyrender draws every primitive with ``flat.vert`` / ``flat.frag`` from the folder given to its
program cache when the ``FLAT`` flag is set; :func:`write_shaders` writes ours there. pyrender
sets the uniforms ``M, V, P, cam_pos`` and the material's fields. Each material names its
surface kind (``material.name``, e.g. ``KIND_SKY``), which the renderer turns into a define, so
each kind compiles to its own shader; ``emissive_factor`` holds ``(detail_per_m, detail_strength, kind)``:

- ``KIND_GROUND``, 0 (fields and grass): albedo = base texture at the mesh UVs x detail texture
  (the emissive slot) sampled at world ``(x, y) * detail_per_m``; lit by sky light and the sun
  on the flat ground; then distance haze;
- ``KIND_SKY``, 1 (sky dome): sky colour from the view direction (gradient, sun glow), clouds from
  the base texture projected on a cloud layer, no haze;
- ``KIND_BUILDING``, 2 (buildings): base colour lit by the sun through the face normal, then haze;
- ``KIND_FLAT``, 3 (flat test scenes): base colour exactly, no light, no haze;
- ``KIND_PAVEMENT``, 4 (runway, taxiways, roads): as 0, with the base texture filtered
  anisotropically in the shader (up to ``SceneParams.anisotropy`` taps along the footprint).

Haze follows Koschmieder: transmittance ``exp(-3.0 d / V)`` over distance ``d`` for a
meteorological optical range ``V`` (5 % contrast), blended towards the horizon sky colour.
"""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from visland.frames import R_ned_from_runway

from .params import SceneParams

__all__ = ["write_shaders", "sun_direction_runway", "sky_colours"]

_VERTEX = """#version 330 core
layout(location = 0) in vec3 position;
#ifdef NORMAL_LOC
layout(location = NORMAL_LOC) in vec3 normal;
#endif
#ifdef TEXCOORD_0_LOC
layout(location = TEXCOORD_0_LOC) in vec2 texcoord_0;
#endif
#ifdef COLOR_0_LOC
layout(location = COLOR_0_LOC) in vec4 color_0;
#endif
layout(location = INST_M_LOC) in mat4 inst_m;

uniform mat4 M;
uniform mat4 V;
uniform mat4 P;

out vec3 frag_position;
out vec3 frag_normal;
out vec2 uv_0;
out vec4 colour_multiplier;

void main()
{
    vec4 world = M * inst_m * vec4(position, 1.0);
    gl_Position = P * V * world;
    frag_position = world.xyz;
#ifdef NORMAL_LOC
    frag_normal = normalize(mat3(M * inst_m) * normal);
#else
    frag_normal = vec3(0.0, 0.0, -1.0);
#endif
#ifdef TEXCOORD_0_LOC
    uv_0 = texcoord_0;
#else
    uv_0 = vec2(0.0);
#endif
#ifdef COLOR_0_LOC
    colour_multiplier = color_0;
#else
    colour_multiplier = vec4(1.0);
#endif
}
"""

_FRAGMENT = """#version 330 core
struct Material {
    vec3 emissive_factor;
    vec4 base_color_factor;
    float metallic_factor;
    float roughness_factor;
#ifdef HAS_EMISSIVE_TEX
    sampler2D emissive_texture;
#endif
#ifdef HAS_BASE_COLOR_TEX
    sampler2D base_color_texture;
#endif
};

uniform Material material;
uniform vec3 cam_pos;

in vec3 frag_position;
in vec3 frag_normal;
in vec2 uv_0;
in vec4 colour_multiplier;
out vec4 frag_color;

const vec3 SUN_DIR = vec3(@SUN_X@, @SUN_Y@, @SUN_Z@);     // towards the sun, runway frame (z down)
const vec3 SKY_ZENITH = vec3(@ZENITH@);
const vec3 SKY_HORIZON = vec3(@HORIZON@);
const vec3 SUN_COLOUR = vec3(@SUN_COLOUR@);
const float AMBIENT = @AMBIENT@;
const float SUN_GAIN = @SUN_GAIN@;
const float EXTINCTION = @EXTINCTION@;                     // 1/m
const float CLOUD_COVER = @CLOUD_COVER@;
const float CLOUD_HEIGHT = 1800.0;
const float CLOUD_SCALE = 9000.0;
const float MAX_TAPS = @MAX_TAPS@;
const float GROUND_LIGHT = AMBIENT + SUN_GAIN * max(-SUN_DIR.z, 0.0);   // flat ground, normal up (-z)

vec3 sky_colour(vec3 dir)
{
    float elevation = -dir.z;
    float t = pow(clamp(elevation, 0.0, 1.0), 0.45);
    vec3 sky = mix(SKY_HORIZON, SKY_ZENITH, t);
    float c = max(dot(dir, SUN_DIR), 0.0);
    sky += SUN_COLOUR * (0.10 * pow(c, 6.0) + 0.35 * pow(c, 200.0));
    return sky;
}

// Anisotropic filtering for the pavement textures only (kind 4): up to MAX_TAPS mipmapped taps
// along the longer axis of the pixel footprint. llvmpipe's built-in anisotropic filtering costs
// about a second per frame; the pavements cover a small part of the image.
vec4 sample_anisotropic(sampler2D tex, vec2 uv)
{
    vec2 size = vec2(textureSize(tex, 0));
    vec2 ddx = dFdx(uv);
    vec2 ddy = dFdy(uv);
    float lx = length(ddx * size);
    float ly = length(ddy * size);
    vec2 major = lx > ly ? ddx : ddy;
    vec2 minor = lx > ly ? ddy : ddx;
    float ratio = max(lx, ly) / max(min(lx, ly), 1e-6);
    float taps = clamp(ceil(ratio), 1.0, MAX_TAPS);
    vec4 sum = vec4(0.0);
    for (int i = 0; i < int(MAX_TAPS); i++) {
        if (float(i) >= taps) break;
        float t = (float(i) + 0.5) / taps - 0.5;
        sum += textureGrad(tex, uv + major * t, major / taps, minor);
    }
    return sum / taps;
}

vec3 haze(vec3 colour)
{
    vec3 to_frag = frag_position - cam_pos;
    float d = length(to_frag);
    float transmittance = exp(-EXTINCTION * d);
    vec3 dir = to_frag / max(d, 1e-3);
    vec3 air = SKY_HORIZON + SUN_COLOUR * 0.08 * pow(max(dot(dir, SUN_DIR), 0.0), 4.0);
    return mix(air, colour, transmittance);
}

void main()
{
    vec4 base = material.base_color_factor * colour_multiplier;
#ifdef KIND_SKY
    vec3 dir = normalize(frag_position - cam_pos);
    vec3 colour = sky_colour(dir);
#ifdef HAS_BASE_COLOR_TEX
    float elevation = -dir.z;
    if (CLOUD_COVER > 0.0 && elevation > 0.0) {
        vec2 uv = (cam_pos.xy + dir.xy * (CLOUD_HEIGHT / max(elevation, 0.03))) / CLOUD_SCALE;
        float density = texture(material.base_color_texture, uv).r;
        float a = smoothstep(1.0 - CLOUD_COVER - 0.05, 1.0 - CLOUD_COVER + 0.30, density);
        a *= smoothstep(0.0, 0.12, elevation);
        vec3 cloud = mix(vec3(0.97, 0.97, 0.98), vec3(0.74, 0.76, 0.80), smoothstep(0.5, 1.0, density));
        colour = mix(colour, cloud, a * 0.92);
    }
#endif
    frag_color = vec4(clamp(colour, 0.0, 1.0), 1.0);
#endif
#ifdef KIND_FLAT
#ifdef HAS_BASE_COLOR_TEX
    base *= texture(material.base_color_texture, uv_0);
#endif
    frag_color = vec4(clamp(base.rgb, 0.0, 1.0), 1.0);
#endif
#ifdef KIND_BUILDING
    float light = AMBIENT + SUN_GAIN * max(dot(normalize(frag_normal), SUN_DIR), 0.0);
    frag_color = vec4(clamp(haze(base.rgb * light * SUN_COLOUR), 0.0, 1.0), 1.0);
#endif
#ifdef KIND_GROUND
#ifdef HAS_BASE_COLOR_TEX
    base *= texture(material.base_color_texture, uv_0);
#endif
#ifdef HAS_EMISSIVE_TEX
    // the detail texture at two incommensurate scales: its tiling does not show
    vec2 p_detail = frag_position.xy * material.emissive_factor.x;
    vec3 detail = texture(material.emissive_texture, p_detail).rgb;
    vec3 detail_large = texture(material.emissive_texture, p_detail * 0.1731 + vec2(0.37, 0.61)).rgb;
    base.rgb *= mix(vec3(1.0), 4.0 * detail * detail_large, material.emissive_factor.y);
#endif
    frag_color = vec4(clamp(haze(base.rgb * GROUND_LIGHT * SUN_COLOUR), 0.0, 1.0), 1.0);
#endif
#ifdef KIND_PAVEMENT
#ifdef HAS_BASE_COLOR_TEX
    base *= sample_anisotropic(material.base_color_texture, uv_0);
#endif
#ifdef HAS_EMISSIVE_TEX
    vec3 detail = texture(material.emissive_texture, frag_position.xy * material.emissive_factor.x).rgb;
    base.rgb *= mix(vec3(1.0), 2.0 * detail, material.emissive_factor.y);
#endif
    frag_color = vec4(clamp(haze(base.rgb * GROUND_LIGHT * SUN_COLOUR), 0.0, 1.0), 1.0);
#endif
}
"""


def sun_direction_runway(params: SceneParams, runway_heading_deg: float) -> np.ndarray:
    """Unit vector towards the sun in the runway frame R (z down).

    Parameters
    ----------
    params : SceneParams
        Its sun azimuth and elevation (degrees, azimuth from north).
    runway_heading_deg : float
        Runway heading, degrees from north.

    Returns
    -------
    ndarray, shape (3,)
    """
    az = math.radians(params.sun_azimuth_deg)
    el = math.radians(params.sun_elevation_deg)
    towards_sun_ned = np.array([math.cos(el) * math.cos(az), math.cos(el) * math.sin(az), -math.sin(el)])
    return R_ned_from_runway(math.radians(runway_heading_deg)).T @ towards_sun_ned


def sky_colours(params: SceneParams) -> tuple[np.ndarray, np.ndarray]:
    """Zenith and horizon sky colours (linear 0-1 RGB as displayed) for the scene's visibility.

    Parameters
    ----------
    params : SceneParams
        Visibility, cloud cover and lighting.

    Returns
    -------
    zenith, horizon : ndarray, shape (3,)
    """
    zenith = np.array([0.30, 0.48, 0.78])
    horizon_clear = np.array([0.73, 0.81, 0.90])
    grey = np.array([0.80, 0.82, 0.84])
    # poorer visibility: a whiter, greyer horizon and a paler zenith
    murk = float(np.clip(1.0 - math.log(params.visibility_m / 300.0) / math.log(30000.0 / 300.0), 0.0, 1.0))
    horizon = horizon_clear * (1 - murk) + grey * murk
    zenith = zenith * (1 - 0.7 * murk) + grey * 0.7 * murk
    cover = 1.0 if params.lighting == "overcast" else params.cloud_cover
    zenith = zenith * (1 - 0.5 * cover) + grey * 0.5 * cover
    if params.lighting == "overcast":
        zenith, horizon = 0.85 * grey, 0.95 * grey
    elif params.lighting == "dusk":
        zenith = 0.45 * zenith + np.array([0.05, 0.06, 0.12])
        horizon = 0.55 * horizon + np.array([0.40, 0.22, 0.10])
    return zenith, horizon


def _vec(v) -> str:
    return ", ".join(f"{float(x):.6f}" for x in v)


def write_shaders(folder, params: SceneParams, runway_heading_deg: float) -> Path:
    """Write ``flat.vert`` and ``flat.frag`` for ``params`` into ``folder``.

    Parameters
    ----------
    folder : str or Path
        Where pyrender will read the shaders.
    params : SceneParams
        Sun, haze, sky and lighting.
    runway_heading_deg : float
        Runway heading, degrees (places the sun in the runway frame).

    Returns
    -------
    Path
        ``folder``.
    """
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    sun = sun_direction_runway(params, runway_heading_deg)
    zenith, horizon = sky_colours(params)
    el = math.radians(params.sun_elevation_deg)
    # warmer, dimmer sun near the horizon
    sun_colour = np.array([1.0, 0.97, 0.92]) if el > math.radians(25) else np.array([1.0, 0.90, 0.78])
    # SceneParams.lighting: overcast is diffuse light (little sun), dusk dim and warm
    ambient, sun_gain, cloud_cover = 0.56, 0.56, params.cloud_cover
    if params.lighting == "overcast":
        ambient, sun_gain, cloud_cover = 0.78, 0.08, 1.0
        sun_colour = np.array([0.97, 0.98, 1.0])
    elif params.lighting == "dusk":
        ambient, sun_gain = 0.30, 0.30
        sun_colour = np.array([1.0, 0.72, 0.50])
    replacements = {
        "@SUN_X@": f"{sun[0]:.6f}", "@SUN_Y@": f"{sun[1]:.6f}", "@SUN_Z@": f"{sun[2]:.6f}",
        "@ZENITH@": _vec(zenith), "@HORIZON@": _vec(horizon), "@SUN_COLOUR@": _vec(sun_colour),
        "@AMBIENT@": f"{ambient:.2f}", "@SUN_GAIN@": f"{sun_gain:.2f}",
        "@EXTINCTION@": f"{2.996 / params.visibility_m:.9e}",
        "@CLOUD_COVER@": f"{cloud_cover:.4f}",
        "@MAX_TAPS@": f"{float(params.anisotropy):.1f}",
    }
    fragment = _FRAGMENT
    for key, value in replacements.items():
        fragment = fragment.replace(key, value)
    (folder / "flat.vert").write_text(_VERTEX)
    (folder / "flat.frag").write_text(fragment)
    return folder
