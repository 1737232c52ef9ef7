"""The Dask cluster behind ``--scheduler`` (``generate``, ``process`` batches, ``campaign``): one way in.

Every command that takes ``--scheduler ADDRESS`` connects through :func:`connect_scheduler`, so
that a missing ``dask.distributed`` or a scheduler that does not answer is the same one sentence
everywhere (SPEC "Bad input"). Tasks never rely on a file system shared with the client: they
return what they make and the client writes it (see each command's module).
"""
from __future__ import annotations

__all__ = ["connect_scheduler", "CONNECT_TIMEOUT_S"]

#: Seconds to wait for the scheduler before saying it cannot be reached.
CONNECT_TIMEOUT_S = 10


def connect_scheduler(address: str, timeout_s: float | None = None):
    """A ``distributed.Client`` connected to the scheduler at ``address`` (not made the default).

    Parameters
    ----------
    address : str
        The scheduler's address, e.g. ``tcp://127.0.0.1:8786``.
    timeout_s : float, optional
        Seconds to wait for it; None: :data:`CONNECT_TIMEOUT_S`.

    Returns
    -------
    distributed.Client
        Close it (or use it as a context manager) when done.

    Raises
    ------
    ValueError
        ``"--scheduler needs dask.distributed, which cannot be imported (...)"`` or
        ``"--scheduler: cannot reach the Dask scheduler at ADDRESS (...)"``.
    """
    try:
        from distributed import Client
    except ImportError as error:
        raise ValueError(f"--scheduler needs dask.distributed, which cannot be imported ({error})") from None
    try:
        return Client(address, timeout=CONNECT_TIMEOUT_S if timeout_s is None else timeout_s, set_as_default=False)
    except (OSError, TimeoutError, ValueError, TypeError) as error:
        raise ValueError(f"--scheduler: cannot reach the Dask scheduler at {address} ({error})") from None
