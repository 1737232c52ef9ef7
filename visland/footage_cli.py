"""Command-line registration of the raw-footage helpers (light: no heavy imports here).

- ``visland calibrate FOOTAGE --board 9x6 --square-mm 25 --out camera.json``: OpenCV's chessboard
  calibration (:mod:`visland.lens`); or ``--hfov-deg`` for a camera.json from a field of view.
- ``visland mask FOOTAGE --out mask.png``: proposes the mask of the aircraft's own structure
  (:mod:`visland.structure_mask`) and a picture to check it.
"""
from __future__ import annotations

import argparse


def _size(text: str) -> tuple[int, int]:
    parts = text.lower().split("x")
    try:
        width, height = (int(p) for p in parts)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected WIDTHxHEIGHT in pixels, e.g. 1280x720, got {text!r}") from None
    return width, height


def _three_angles(text: str) -> tuple[float, float, float]:
    try:
        values = tuple(float(p) for p in text.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected three comma-separated degrees R,P,Y, got {text!r}") from None
    if len(values) != 3:
        raise argparse.ArgumentTypeError(f"expected three comma-separated degrees R,P,Y, got {text!r}")
    return values


def _check_out(path, force: bool):
    from pathlib import Path
    out = Path(path)
    if out.is_dir():
        raise ValueError(f"{out}: is a folder; --out names the camera.json file to write")
    if out.exists() and not force:
        raise ValueError(f"{out}: output file exists; choose another --out or pass --force to replace it")
    if not out.parent.is_dir():
        raise ValueError(f"{out.parent}: folder not found for --out")
    return out


def _lens_from_lines(args, camera):
    """``camera`` with the k1 of the straight edges in the footage (plumb-line, :mod:`visland.lens`)."""
    from dataclasses import replace

    import cv2

    from visland.footage import sample_footage
    from visland.lens import estimate_k1_from_lines
    count = args.examine or 20
    if count < 1:
        raise ValueError(f"--examine must be at least 1 frame, got {count}")
    frames, total = sample_footage(args.footage, count)
    ignore = None
    if args.mask:
        image = cv2.imread(str(args.mask), cv2.IMREAD_GRAYSCALE)
        if image is None:
            raise ValueError(f"{args.mask}: unreadable mask image")
        if image.shape != (camera.height, camera.width):
            raise ValueError(f"{args.mask}: mask is {image.shape[1]}x{image.shape[0]} but the frames are "
                             f"{camera.width}x{camera.height}")
        ignore = image > 127
    result = estimate_k1_from_lines([f.image for f in frames], camera.fx, camera.fy, camera.cx, camera.cy,
                                    ignore=ignore)
    print(f"{args.footage}: {total} frames, {len(frames)} searched for straight edges; k1 {result.k1:.4f} from "
          f"{result.pieces} edge pieces (RMS distance to their lines {result.straightness_before_px:.3f} px "
          f"without distortion, {result.straightness_after_px:.3f} px with)")
    return replace(camera, distortion=(result.k1, 0.0, 0.0, 0.0, 0.0))


def _cmd_calibrate(args) -> int:
    import math

    from visland.camera import CameraModel
    from visland.footage import sample_footage
    out = _check_out(args.out, args.force)
    if args.hfov_deg is not None:
        if args.footage is None and args.size is None:
            raise ValueError("--hfov-deg needs the frame size: give --size WxH or the footage")
        if args.lines and args.footage is None:
            raise ValueError("--lines needs footage to find straight edges in")
        if args.mask and not args.lines:
            raise ValueError("--mask goes with --lines (the structure's edges are left out of the line fit)")
        size = args.size
        if args.footage is not None:
            frames, _ = sample_footage(args.footage, 1)
            height, width = frames[0].image.shape[:2]
            if size is not None and size != (width, height):
                raise ValueError(f"--size {size[0]}x{size[1]} but {frames[0].name} is {width}x{height}")
            size = (width, height)
        camera = CameraModel.from_fov(size[0], size[1], args.hfov_deg, mount_rpy_deg=args.mount_deg)
        if args.lines:
            camera = _lens_from_lines(args, camera)
        camera.save(out)
        lens = (f"distortion k1 {camera.distortion[0]:.4f} from straight edges" if args.lines else "no distortion")
        print(f"camera from a {args.hfov_deg:g} deg horizontal field of view: {camera.width}x{camera.height}, "
              f"fx = fy = {camera.fx:.2f} px, principal point at the centre, {lens} (a guess: calibrate with a "
              f"chessboard when you can)")
        print(f"wrote {out}")
        return 0
    if args.lines or args.mask:
        raise ValueError("--lines and --mask go with --hfov-deg (a camera from a field of view)")
    from visland.lens import calibrate_views, find_board_views, parse_board
    if args.footage is None:
        raise ValueError("give the chessboard footage (a video or a folder of images), or --hfov-deg for a "
                         "camera from a field of view")
    if args.size is not None:
        raise ValueError("--size goes with --hfov-deg; a calibration takes the size from the footage")
    board = parse_board(args.board)
    if args.square_mm is None or not (math.isfinite(args.square_mm) and args.square_mm > 0):
        raise ValueError(f"--square-mm must be the positive side of a board square in millimetres, got {args.square_mm}")
    if args.examine is not None and args.examine < 1:
        raise ValueError(f"--examine must be at least 1 frame, got {args.examine}")
    frames, total = sample_footage(args.footage, args.examine or 200)
    views = find_board_views(frames, board)
    if not views:
        raise ValueError(f"{args.footage}: no {args.board} chessboard found in any of the {len(frames)} frames "
                         f"examined (--board counts inner corners, squares minus one; the whole board must be "
                         f"in view)")
    height, width = frames[0].image.shape[:2]
    print(f"{args.footage}: {total} frames, {len(frames)} examined, board found in {len(views)}")
    result = calibrate_views(views, board, args.square_mm / 1000.0, (width, height), max_views=args.max_views,
                             mount_rpy_deg=args.mount_deg)
    for line in result.summary_lines():
        print(line)
    if result.rms_px > 1.0:
        print("RMS above 1 px: blurred or badly lit views, or a board that is not flat; check the footage")
    result.camera.save(out)
    print(f"wrote {out}")
    return 0


def _cmd_mask(args) -> int:
    import os
    from pathlib import Path

    import cv2
    import numpy as np

    from visland.camera import CameraModel
    from visland.footage import sample_footage
    from visland.structure_mask import MaskParams, mask_picture, propose_structure_mask
    out = Path(args.out)
    if out.suffix.lower() != ".png":
        raise ValueError(f"{out}: --out names the mask to write, a .png file")
    if out.is_dir() or not out.parent.is_dir():
        raise ValueError(f"{out}: --out must be a .png file in an existing folder")
    picture = Path(args.picture) if args.picture else out.with_name(out.stem + "-check.png")
    for path in (out, picture):
        if path.exists() and not args.force:
            raise ValueError(f"{path}: output file exists; choose another --out or pass --force to replace it")
    camera_data = None
    if args.camera:
        from visland.userfiles import read_json_object
        camera_data = read_json_object(Path(args.camera), "camera file")
        # the mask this command is about to (re)write is not read: it may not exist yet
        camera = CameraModel.from_json_dict({k: v for k, v in camera_data.items() if k != "mask"},
                                            source=str(args.camera))
    else:
        camera = None
    if args.update_camera and camera is None:
        raise ValueError("--update-camera needs --camera FILE (the camera.json to add the mask to)")
    overrides = {name: getattr(args, name) for name in ("max_static_std", "dilate_px") if getattr(args, name) is not None}
    params = MaskParams(**overrides)
    if args.samples < 5:
        raise ValueError(f"--samples must be at least 5 frames, got {args.samples}")
    frames, total = sample_footage(args.footage, args.samples, colour=True)
    height, width = frames[0].image.shape[:2]
    if camera is not None and (camera.width, camera.height) != (width, height):
        raise ValueError(f"{args.camera}: camera is {camera.width}x{camera.height} but the frames of "
                         f"{args.footage} are {width}x{height}")
    greys = [cv2.cvtColor(f.image, cv2.COLOR_RGB2GRAY) for f in frames]
    result = propose_structure_mask(greys, params, source=str(args.footage))
    shown = frames[len(frames) // 2]
    cv2.imwrite(str(out), np.where(result.mask, 255, 0).astype(np.uint8))
    cv2.imwrite(str(picture), cv2.cvtColor(mask_picture(shown.image, result.mask), cv2.COLOR_RGB2BGR))
    print(f"{args.footage}: {total} frames, {len(frames)} sampled")
    print(result.summary())
    print(f"wrote {out} (white = aircraft structure, ignored) and {picture} ({shown.name} | mask tinted): check it")
    camera_dir = Path(args.camera).parent if args.camera else out.parent
    relative = os.path.relpath(out.resolve(), camera_dir.resolve())
    where = args.camera if args.camera else str(camera_dir / "camera.json")
    if result.coverage == 0.0:
        print("no structure found (nothing steady and dark or edged touches the image border): no mask needed, "
              "or draw polygons by hand")
        return 0
    if args.update_camera:
        import json
        camera_data["mask"] = relative
        Path(args.camera).write_text(json.dumps(camera_data, indent=2) + "\n")
        print(f"{args.camera}: \"mask\": \"{relative}\" set")
    else:
        print(f"add to {where}: \"mask\": \"{relative}\" (or rerun with --update-camera)")
    return 0


def register(subparsers):
    """Add the footage helpers' commands (``calibrate``, ``mask``) to the visland parser.

    Parameters
    ----------
    subparsers : argparse._SubParsersAction
        Gains ``calibrate`` and ``mask`` (raw footage in, ``camera.json`` or a mask out).
    """
    p = subparsers.add_parser(
        "calibrate", help="camera.json with lens distortion from chessboard footage (or from a field of view)",
        description="OpenCV's ordinary chessboard calibration: frames sampled evenly over a video or a folder of "
                    "images (DIR/frames/ if present, else DIR) are searched for the board "
                    "(findChessboardCorners, cornerSubPix); at most --max-views of the views found, spread over "
                    "the footage, go to calibrateCamera (fx, fy, cx, cy and k1, k2, p1, p2, k3). Writes camera.json "
                    "(SPEC format, with \"distortion\") and prints the RMS reprojection error and the views used. "
                    "Without a calibration, --hfov-deg writes a pinhole camera from the horizontal field of view "
                    "(size from --size or the footage); with --lines, k1 is estimated from edges straight in the world.")
    p.add_argument("footage", nargs="?", metavar="VIDEO|DIR", help="chessboard video or folder of images")
    p.add_argument("--out", required=True, metavar="FILE", help="camera.json to write (refused if it exists)")
    p.add_argument("--board", default="9x6", metavar="COLSxROWS",
                   help="inner corners of the chessboard (squares minus one), default 9x6")
    p.add_argument("--square-mm", type=float, default=None, metavar="MM",
                   help="side of one square in millimetres (required for a calibration)")
    p.add_argument("--max-views", type=int, default=40, metavar="N",
                   help="most board views used, spread over the footage (default 40)")
    p.add_argument("--examine", type=int, default=None, metavar="N",
                   help="frames searched for the board (default 200) or for straight edges (--lines, default 20), "
                        "spread over the footage")
    p.add_argument("--mount-deg", type=_three_angles, default=(0.0, 0.0, 0.0), metavar="R,P,Y",
                   help="camera mounting on the body written to camera.json, degrees (default 0,0,0)")
    p.add_argument("--hfov-deg", type=float, default=None, metavar="DEG",
                   help="no calibration: camera from this horizontal field of view (no distortion)")
    p.add_argument("--size", type=_size, default=None, metavar="WxH", help="frame size for --hfov-deg without footage")
    p.add_argument("--lines", action="store_true",
                   help="with --hfov-deg and footage: estimate k1 from edges straight in the world (field "
                        "boundaries, roads, runway edges, horizon) that the lens bends")
    p.add_argument("--mask", metavar="PNG", help="with --lines: the aircraft's structure (visland mask), left out")
    p.add_argument("--force", action="store_true", help="replace an existing output file")
    p.set_defaults(func=_cmd_calibrate)

    p = subparsers.add_parser(
        "mask", help="propose a mask of the aircraft's own structure (windshield frame, wiper) from footage",
        description="Frames sampled evenly over a video or a folder of images: pixels that stay put while the "
                    "scene moves (low temporal variance) and are dark or next to a static edge are the aircraft's "
                    "structure; a uniform bright sky, as steady, is not taken. Cleaned up (thin bands removed, "
                    "parts touching the image border kept, small holes filled, slightly dilated). Writes the mask "
                    "(PNG, white = structure, the frames' size), a picture frame | frame with the mask tinted to "
                    "check it, and prints the line to add to camera.json.")
    p.add_argument("footage", metavar="VIDEO|DIR", help="video, or folder of images (DIR/frames/ if present)")
    p.add_argument("--out", required=True, metavar="FILE.png", help="mask to write (refused if it exists)")
    p.add_argument("--picture", metavar="FILE.png", help="check picture (default: OUT with -check before .png)")
    p.add_argument("--camera", metavar="FILE", help="camera.json the mask goes with (checks the size; the printed "
                                                     "path is relative to its folder)")
    p.add_argument("--update-camera", action="store_true",
                   help="write the \"mask\" field into the --camera file instead of printing the line")
    p.add_argument("--samples", type=int, default=40, metavar="N",
                   help="frames sampled evenly over the footage (default 40)")
    p.add_argument("--max-static-std", type=float, default=None, metavar="GREY",
                   help="largest temporal standard deviation of a static pixel, grey levels (default 6)")
    p.add_argument("--dilate-px", type=int, default=None, metavar="PX",
                   help="final dilation of the mask (default 0.3 %% of the short side, at least 1 px)")
    p.add_argument("--force", action="store_true", help="replace existing output files")
    p.set_defaults(func=_cmd_mask)
