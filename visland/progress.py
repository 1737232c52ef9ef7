"""Progress bars of the long commands (generate, detect, track, process): one tqdm bar on stderr.

The bar is drawn only on a terminal: when stderr is a file or a pipe (a log, a batch job) it
stays silent, so no carriage returns end up in log files; the commands print their own summary
line when they finish.
"""
from __future__ import annotations

__all__ = ["progress_bar"]


def progress_bar(total: int, label: str, initial: int = 0, enabled: bool = True):
    """A tqdm bar counting frames on stderr.

    Parameters
    ----------
    total : int
        Number of frames of the whole job.
    label : str
        What is being done, shown before the bar (``"render"``, ``"detect"``, ``"track"``).
    initial : int
        Frames already done before this run (a resumed job).
    enabled : bool
        False silences the bar whatever stderr is (``--quiet``, tests).

    Returns
    -------
    tqdm.tqdm
        Call ``update(n)`` as frames are done and ``close()`` at the end (or use it as a
        context manager).
    """
    from tqdm import tqdm          # imported here: `visland simulate` starts without it
    return tqdm(total=total, initial=initial, desc=label, unit="frame", mininterval=0.25, dynamic_ncols=True,
                disable=None if enabled else True)       # None: disabled when stderr is not a terminal
