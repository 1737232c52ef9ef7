"""Contact sheet of an approach: frames rendered at 2048x2048 from 5 km to 100 ft, downscaled.

Writes docs/contact_sheet.png (palette PNG, under 300 KB) with the distance to the threshold
and the height above the runway under each frame, a magnified inset of the runway where it is
small (its source outlined on the tile), and a 1:1 crop of the 100 ft frame's threshold so the
markings can be judged at full resolution.

    .venv/bin/python benchmarks/render_contact_sheet.py [SCENARIO] [OUT]
"""
import json
import sys
from pathlib import Path

import cv2
import numpy as np

ROOT = Path(__file__).resolve().parents[1]


def main():
    from PIL import Image
    from visland.camera import CameraModel
    from visland.features import batch_R_camera_from_runway
    from visland.flight import FT_TO_M
    from visland.render import FrameRenderer, SceneParams
    from visland.scenarios import get_scenario
    from visland.simulate import SimulationOptions, run_simulation

    scenario = sys.argv[1] if len(sys.argv) > 1 else "thesis-1"
    out = Path(sys.argv[2]) if len(sys.argv) > 2 else ROOT / "docs" / "contact_sheet.png"
    camera = CameraModel.default(2048)
    result = run_simulation(get_scenario(scenario), SimulationOptions(fps=25.0, camera=camera))
    s = result.frames
    R_cr = batch_R_camera_from_runway(s.roll_rad, s.pitch_rad, s.dpsi_rad, camera.mount_rpy_rad)
    distance = np.hypot(s.p_runway_m[:, 0], s.p_runway_m[:, 1])
    height = -s.p_runway_m[:, 2]
    picks = [int(np.argmin(np.abs(distance - d))) for d in (5000.0, 3000.0, 2000.0, 1000.0, 500.0)]
    picks.append(int(np.nonzero(height <= 100.0 * FT_TO_M)[0][0]))
    tile = 300
    tiles, captions = [], []
    with FrameRenderer(SceneParams(), camera, result.scenario.runway) as renderer:
        for i in picks:
            rgb = renderer.render(s.p_runway_m[i], R_cr[i], frame_seed=i)
            small = cv2.resize(rgb, (tile, tile), interpolation=cv2.INTER_AREA)
            _add_inset(small, rgb, result.features.corners_uv[i])
            caption = f"{distance[i] / 1000:.1f} km, {height[i] / FT_TO_M:.0f} ft"
            band = np.full((22, tile, 3), 255, np.uint8)
            cv2.putText(band, caption, (6, 16), cv2.FONT_HERSHEY_SIMPLEX, 0.48, (0, 0, 0), 1, cv2.LINE_AA)
            tiles.append(np.vstack([small, band]))
            captions.append(caption)
        # full-resolution crop around the threshold in the last frame
        uv = result.features.corners_uv[picks[-1], :2].mean(axis=0)
        u, v = int(round(uv[0])), int(round(uv[1]))
        crop = rgb[max(0, v - 200):v + 100, max(0, u - 300):u + 300]
        crop = cv2.resize(crop, (2 * tile, tile), interpolation=cv2.INTER_AREA) if crop.shape[:2] != (tile, 2 * tile) else crop
    band = np.full((22, 2 * tile, 3), 255, np.uint8)
    cv2.putText(band, "100 ft: threshold at full resolution (1:1 crop)", (6, 16), cv2.FONT_HERSHEY_SIMPLEX, 0.48,
                (0, 0, 0), 1, cv2.LINE_AA)
    rows = [np.hstack(tiles[0:3]), np.hstack(tiles[3:6])]
    crop_row = np.hstack([np.vstack([crop, band]), np.full((tile + 22, tile, 3), 255, np.uint8)])
    sheet = np.vstack(rows + [crop_row])
    image = Image.fromarray(sheet).quantize(colors=192, method=Image.Quantize.MEDIANCUT, dither=Image.Dither.FLOYDSTEINBERG)
    out.parent.mkdir(parents=True, exist_ok=True)
    image.save(out, optimize=True)
    print(json.dumps({"contact_sheet": str(out), "bytes": out.stat().st_size, "frames": picks, "captions": captions}))


def _add_inset(small, rgb, corners_uv, inset_px: int = 124, min_side_px: int = 160):
    """Paste a magnified view of the runway into the tile's lower right corner when the runway
    is small in the frame, and outline on the tile where it comes from."""
    uv = corners_uv[np.isfinite(corners_uv).all(axis=1)]
    if len(uv) < 2:
        return
    lo, hi = uv.min(axis=0), uv.max(axis=0)
    side = max(float((hi - lo).max()) * 1.5, float(min_side_px))
    scale = small.shape[0] / rgb.shape[0]
    if inset_px / side / scale < 1.5:
        return                                           # big enough to see in the tile
    centre = 0.5 * (lo + hi)
    u0 = int(np.clip(centre[0] - side / 2, 0, rgb.shape[1] - side))
    v0 = int(np.clip(centre[1] - side / 2, 0, rgb.shape[0] - side))
    n = int(side)
    inset = cv2.resize(rgb[v0:v0 + n, u0:u0 + n], (inset_px, inset_px), interpolation=cv2.INTER_AREA)
    cv2.rectangle(small, (int(u0 * scale), int(v0 * scale)), (int((u0 + n) * scale), int((v0 + n) * scale)),
                  (255, 255, 255), 1)
    h, w = small.shape[:2]
    small[h - inset_px - 6:h - 2, w - inset_px - 6:w - 2] = 255
    small[h - inset_px - 4:h - 4, w - inset_px - 4:w - 4] = inset
    magnification = inset_px / n / scale                  # relative to the tile
    cv2.putText(small, f"x{magnification:.0f}", (w - inset_px - 4, h - inset_px - 10),
                cv2.FONT_HERSHEY_SIMPLEX, 0.45, (255, 255, 255), 1, cv2.LINE_AA)


if __name__ == "__main__":
    main()
