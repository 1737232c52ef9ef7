"""What the user hands in: paths checked up front, JSON and TOML documents read in one sentence.

Every command checks each path it was given before any work starts (a file that must be a
file, a folder that must be a folder, an output whose parent must be a writable folder), so a
run never fails after minutes of measuring because ``--out`` names ``/proc/x`` or a path
below a regular file. Every error is one ``ValueError`` sentence naming the path as the user
gave it and what was wanted.

JSON and TOML documents are read as UTF-8 with an optional byte-order mark (spreadsheets and
some editors write one), must hold an object (a table) at the top level, and a read error
names the file and the line.

This module imports nothing from visland (every reader may use it).
"""
from __future__ import annotations

import json
import os
import tempfile
import tomllib
from pathlib import Path

__all__ = ["read_json_object", "read_toml_object", "read_document_text", "check_input_file", "check_input_folder",
           "check_output_file", "check_output_folder"]


def read_document_text(path, what: str = "file") -> str:
    """The text of ``path`` (UTF-8, a leading byte-order mark dropped); one sentence on failure.

    Parameters
    ----------
    path : str or Path
        The user's file.
    what : str, default "file"
        What the file is, in the error ("scenario file", "camera.json"...).

    Returns
    -------
    str
    """
    path = Path(path)
    try:
        data = path.read_bytes()
    except FileNotFoundError:
        raise ValueError(f"{path}: {what} not found") from None
    except IsADirectoryError:
        raise ValueError(f"{path}: is a folder, expected the {what}") from None
    except PermissionError:
        raise ValueError(f"{path}: {what} cannot be read (permission denied)") from None
    except OSError as error:
        raise ValueError(f"{path}: {what} cannot be read ({error.strerror or error})") from None
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as error:
        raise ValueError(f"{path}: {what} is not UTF-8 text (byte {error.start} is 0x{data[error.start]:02x})") from None


def read_json_object(path, what: str = "JSON file") -> dict:
    """A JSON document whose top level is an object, as a dict.

    Parameters
    ----------
    path : str or Path
        The JSON file.
    what : str, default "JSON file"
        Its role, named when it is missing, unreadable or not an object.

    Returns
    -------
    dict
    """
    path = Path(path)
    text = read_document_text(path, what)
    try:
        data = json.loads(text)
    except json.JSONDecodeError as error:
        raise ValueError(f"{path}: not valid JSON ({error.msg} at line {error.lineno})") from None
    except RecursionError:
        raise ValueError(f"{path}: not valid JSON (nested too deeply)") from None
    if not isinstance(data, dict):
        raise ValueError(f"{path}: the {what} must hold a JSON object {{...}}, found a {type(data).__name__}")
    return data


def read_toml_object(path, what: str = "TOML file") -> dict:
    """A TOML document as a dict.

    Parameters
    ----------
    path : str or Path
        The TOML file (parameters, scenario, column map).
    what : str, default "TOML file"
        Its role in the error sentence.

    Returns
    -------
    dict
        The document's tables as nested dicts.
    """
    path = Path(path)
    text = read_document_text(path, what)
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as error:
        raise ValueError(f"{path}: not valid TOML ({error})") from None
    except RecursionError:
        raise ValueError(f"{path}: not valid TOML (nested too deeply)") from None


def check_input_file(path, what: str = "file", option: str | None = None) -> Path:
    """``path`` as a Path, after checking it is an existing regular file that can be read.

    Parameters
    ----------
    path : str or Path
        The file a command was given.
    what : str, default "file"
        Its role, in the error.
    option : str, optional
        The command-line option that named it (``--camera``...), put before the path in errors.

    Returns
    -------
    Path
    """
    path = Path(path)
    named = f"{option} {path}" if option else str(path)
    if not path.exists():
        if path.is_symlink():
            raise ValueError(f"{named}: the {what} is a dangling link")
        raise ValueError(f"{named}: {what} not found")
    if path.is_dir():
        raise ValueError(f"{named}: is a folder, expected the {what}")
    if not path.is_file():
        raise ValueError(f"{named}: not a regular file, expected the {what}")
    if not os.access(path, os.R_OK):
        raise ValueError(f"{named}: the {what} cannot be read (permission denied)")
    return path


def check_input_folder(path, what: str = "input folder", option: str | None = None) -> Path:
    """``path`` as a Path, after checking it is an existing folder that can be listed.

    Parameters
    ----------
    path : str or Path
        The folder a command reads.
    what : str, default "input folder"
        Its role, in the error.
    option : str, optional
        The option that named it, if any.

    Returns
    -------
    Path
        The folder, readable and listable.
    """
    path = Path(path)
    named = f"{option} {path}" if option else str(path)
    if not path.exists():
        raise ValueError(f"{named}: {what} not found")
    if not path.is_dir():
        raise ValueError(f"{named}: is a file, expected the {what}")
    if not os.access(path, os.R_OK | os.X_OK):
        raise ValueError(f"{named}: the {what} cannot be read (permission denied)")
    return path


def _check_parent(path: Path, named: str) -> None:
    parent = path.parent if str(path.parent) else Path(".")
    # walk up to the first existing ancestor: it must be a folder we may create entries in
    ancestor = parent
    while not ancestor.exists() and not ancestor.is_symlink():
        if ancestor.parent == ancestor:
            break
        ancestor = ancestor.parent
    if ancestor.is_symlink() and not ancestor.exists():
        raise ValueError(f"{named}: {ancestor} is a dangling link")
    if not ancestor.is_dir():
        raise ValueError(f"{named}: {ancestor} is a file, so nothing can be written below it")
    try:                     # a real probe: permission bits say nothing for root or on /proc
        fd, probe = tempfile.mkstemp(prefix=".visland-probe-", dir=ancestor)
    except OSError:
        raise ValueError(f"{named}: folder {ancestor} is not writable") from None
    os.close(fd)
    os.unlink(probe)


def check_output_file(path, force: bool = False, what: str = "output file", option: str = "--out") -> Path:
    """``path`` as a Path, after checking a file can be written there: not a folder, not
    existing unless ``force``, its folder exists (or can be made) and is writable.

    Parameters
    ----------
    path : str or Path
        Where the command will write.
    force : bool, default False
        Whether an existing file may be replaced.
    what : str, default "output file"
        The file's role, in the error.
    option : str, default "--out"
        The option that named it.

    Returns
    -------
    Path
    """
    path = Path(path)
    named = f"{option} {path}"
    if path.is_dir():
        raise ValueError(f"{named}: is a folder, expected the {what} to write")
    if (path.exists() or path.is_symlink()) and not force:
        raise ValueError(f"{path}: output file exists; choose another {option} or pass --force to replace it")
    _check_parent(path, named)
    return path


def check_output_folder(path, force: bool = False, what: str = "output folder", option: str = "--out") -> Path:
    """``path`` as a Path, after checking a folder can be made there: not existing unless
    ``force`` (and then a folder), its parent exists (or can be made) and is writable.

    Parameters
    ----------
    path : str or Path
        The folder the command will create.
    force : bool, default False
        Whether an existing folder may be replaced.
    what : str, default "output folder"
        Named in the error.
    option : str, default "--out"
        The option that gave the path.

    Returns
    -------
    Path
    """
    path = Path(path)
    named = f"{option} {path}"
    if path.exists() or path.is_symlink():
        if not force:
            raise ValueError(f"{path}: output folder exists; choose another {option} or pass --force to replace it")
        if not path.is_dir():
            raise ValueError(f"{named}: is a file, expected the {what}")
    _check_parent(path, named)
    return path
