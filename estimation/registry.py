"""Observer names (SPEC.md "Command line") mapped to their classes, imported lazily.

Two points: oj-2p ii-2p cccs-2p ccpi-hg-2p ccpi-hosm-2p cccj-2p kf-2p
(:mod:`visland.estimation.points`, :mod:`visland.estimation.kalman`); two lines: oj-2l ii-2l
ccpi-2l cccj-2l ekf-2l (:mod:`visland.estimation.lines`); the ECC'15 system: ecc-hg ecc-hosm
(:mod:`visland.estimation.ecc`); the 4D approach of seed 004: dickmanns-4d
(:mod:`visland.estimation.dickmanns`).
"""
from __future__ import annotations

import importlib
import math

from visland.estimation.base import Observer

__all__ = ["OBSERVERS", "OBSERVER_NAMES", "POINT_OBSERVERS", "LINE_OBSERVERS", "ECC_OBSERVERS", "DICKMANNS_OBSERVERS", "PIXEL_ANGLE_FIELDS", "params_for_camera",
           "observer_class", "make_observer", "observer_features"]

#: name -> (module, class, features)
OBSERVERS = {
    "oj-2p": ("visland.estimation.points", "OJ2P", "points"),
    "ii-2p": ("visland.estimation.points", "II2P", "points"),
    "cccs-2p": ("visland.estimation.points", "CCCS2P", "points"),
    "ccpi-hg-2p": ("visland.estimation.points", "CCPIHG2P", "points"),
    "ccpi-hosm-2p": ("visland.estimation.points", "CCPIHOSM2P", "points"),
    "cccj-2p": ("visland.estimation.points", "CCCJ2P", "points"),
    "kf-2p": ("visland.estimation.kalman", "KF2P", "points"),
    "oj-2l": ("visland.estimation.lines", "OJ2L", "lines"),
    "ii-2l": ("visland.estimation.lines", "II2L", "lines"),
    "ccpi-2l": ("visland.estimation.lines", "CCPI2L", "lines"),
    "cccj-2l": ("visland.estimation.lines", "CCCJ2L", "lines"),
    "ekf-2l": ("visland.estimation.lines", "EKF2L", "lines"),
    "ecc-hg": ("visland.estimation.ecc", "EccHG", "points"),
    "ecc-hosm": ("visland.estimation.ecc", "EccHOSM", "points"),
    "dickmanns-4d": ("visland.estimation.dickmanns", "Dickmanns4D", "lines"),
}
OBSERVER_NAMES = tuple(OBSERVERS)
POINT_OBSERVERS = tuple(n for n in OBSERVER_NAMES if n.endswith("-2p"))
LINE_OBSERVERS = tuple(n for n in OBSERVER_NAMES if n.endswith("-2l"))
ECC_OBSERVERS = ("ecc-hg", "ecc-hosm")
DICKMANNS_OBSERVERS = ("dickmanns-4d",)


def observer_features(name: str) -> str:
    """"points" or "lines" for a SPEC observer name.

    Parameters
    ----------
    name : str
        A SPEC observer name (``kf-2p``, ``ekf-2l``...; :data:`OBSERVER_NAMES`).

    Returns
    -------
    str
        ``"points"`` or ``"lines"``: the features it reads.
    """
    return _entry(name)[2]


def _entry(name: str):
    try:
        return OBSERVERS[name]
    except KeyError:
        raise ValueError(f"unknown observer '{name}'; known: {' '.join(OBSERVER_NAMES)}") from None


def observer_class(name: str) -> type:
    """The class implementing observer ``name`` (imports its module on first use).

    Parameters
    ----------
    name : str
        One of :data:`OBSERVER_NAMES`; another raises ``ValueError`` listing them.

    Returns
    -------
    type
        A subclass of :class:`visland.estimation.base.Observer`.
    """
    module_name, class_name, _ = _entry(name)
    try:
        module = importlib.import_module(module_name)
    except ModuleNotFoundError as error:
        if error.name == module_name:
            raise ValueError(f"observer '{name}' is not available: module {module_name} is missing") from None
        raise
    cls = getattr(module, class_name, None)
    if cls is None:
        raise ValueError(f"observer '{name}' is not available: {module_name} has no {class_name}")
    if not (isinstance(cls, type) and issubclass(cls, Observer)):
        raise ValueError(f"observer '{name}': {module_name}.{class_name} is not an Observer")
    return cls


#: Parameter fields given as an image angle whose default is a number of the SPEC camera's pixels
#: (1 px = 1 / DEFAULT_FOCAL_PX rad): on another camera the same number of *its* pixels is meant.
PIXEL_ANGLE_FIELDS = ("image_sigma_rad", "noise_sigma_rad")


def params_for_camera(name: str, fx_px: float, params=None):
    """``params`` of observer ``name`` with every pixel-angle field (:data:`PIXEL_ANGLE_FIELDS`)
    the caller did not set scaled from the SPEC camera's pixel to a pixel of focal ``fx_px``.

    kf-2p's and dickmanns-4d's image noise defaults to one pixel of the SPEC camera (1/2472 rad);
    on a 512 px camera (fx 618 px) a detected corner's pixel of noise is four times that angle,
    and a filter told a quarter of it trusts its corners four times too much.

    Parameters
    ----------
    name : str
        One of :data:`OBSERVER_NAMES`.
    fx_px : float
        Focal length of the camera the measurements come from, pixels.
    params : dict or dataclass, optional
        The caller's parameters: a dataclass is returned as it is (every field chosen), a dict
        keeps the fields it sets.

    Returns
    -------
    dict or dataclass
    """
    from visland.camera import DEFAULT_FOCAL_PX
    if params is not None and not isinstance(params, dict):
        return params
    if not (math.isfinite(fx_px) and fx_px > 0):
        raise ValueError(f"fx_px must be a positive focal length in pixels, got {fx_px!r}")
    chosen = dict(params or {})
    defaults = observer_class(name).params_type()
    for field in PIXEL_ANGLE_FIELDS:
        if field not in chosen and hasattr(defaults, field):
            chosen[field] = getattr(defaults, field) * DEFAULT_FOCAL_PX / fx_px
    return chosen


def make_observer(name: str, params=None) -> Observer:
    """A fresh observer ``name`` with ``params``.

    Parameters
    ----------
    name : str
        One of :data:`OBSERVER_NAMES`.
    params : dataclass or dict, optional
        Its parameter dataclass, a dict of its fields, or None for the defaults.

    Returns
    -------
    visland.estimation.base.Observer
    """
    return observer_class(name)(params)
