"""Downloading a third-party data set with pooch, every file checked against its SHA-256."""

from __future__ import annotations

import logging
from contextlib import contextmanager
from pathlib import Path

from .registry import Dataset
from .store import DataUnavailableError

log = logging.getLogger("clothsim.datasets")
TIMEOUT = 30.0  # seconds without an answer before a download gives up


@contextmanager
def _quiet_pooch():
    """pooch logs every download on stderr by itself; clothsim logs its own lines."""
    import pooch

    logger = pooch.get_logger()
    level = logger.level
    logger.setLevel(logging.WARNING)
    try:
        yield pooch
    finally:
        logger.setLevel(level)


def _reason(exc: BaseException) -> str:
    """A short cause of a failed download (requests' own messages run to several lines)."""
    import requests

    if isinstance(exc, requests.HTTPError) and exc.response is not None:
        return f"HTTP {exc.response.status_code}"
    if isinstance(exc, requests.Timeout):
        return f"no answer within {TIMEOUT:g} s"
    if isinstance(exc, requests.ConnectionError):
        return "no connection"
    if isinstance(exc, ValueError) and "hash" in str(exc).lower():
        return "the file does not match its pinned SHA-256"
    return " ".join(str(exc).split())[:200] or type(exc).__name__


def _remove_if_empty(folder: Path) -> None:
    try:
        folder.rmdir()
    except OSError:
        pass


def fetch_files(ds: Dataset, folder: Path, base_url: str | None, how: str) -> Path:
    """Download every file of ``ds`` missing from ``folder`` or not matching its SHA-256.

    Parameters
    ----------
    ds : Dataset
        A third-party data set (with a ``url``).
    folder : Path
        Where its files go (made if missing; an empty one is removed again on failure).
    base_url : str or None
        A mirror to download from instead of ``ds.url``.
    how : str
        How to get the data set otherwise, the end of the error message.

    Returns
    -------
    Path
        ``folder``, holding every file, each matching its SHA-256.

    Raises
    ------
    DataUnavailableError
        One line: the file, the URL, the short cause (no connection, HTTP status, no
        answer, SHA-256 mismatch) and ``how``. A file that failed is not kept.
    """
    url = base_url or ds.url
    url = url if url.endswith("/") else url + "/"
    with _quiet_pooch() as pooch:
        repo = pooch.create(path=folder, base_url=url, retry_if_failed=1,
                            registry={f: f"sha256:{h}" for f, h in ds.files.items()})
        downloader = pooch.HTTPDownloader(progressbar=False, timeout=TIMEOUT)
        for f in ds.files:
            try:
                repo.fetch(f, downloader=downloader)
            except (OSError, ValueError) as exc:  # requests' errors are OSErrors
                log.debug("download of %s failed", f, exc_info=True)
                _remove_if_empty(folder)
                raise DataUnavailableError(
                    f"data set {ds.name}: could not download {f} from {url} "
                    f"({_reason(exc)}); {how}") from None
    log.info("%s: %d files in %s", ds.name, len(ds.files), folder)
    return folder
