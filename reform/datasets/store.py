"""Datasets in object storage: a URI (``s3://bucket/prefix``, ``gs://…``, ``memory://…``, any
fsspec filesystem) opened as a `Store`, the few operations a generated dataset needs.

Credentials and endpoints come from where each filesystem's own library looks for them, never
from the URI or the command line: for S3 (s3fs, botocore) the environment variables
``AWS_ACCESS_KEY_ID``, ``AWS_SECRET_ACCESS_KEY``, ``AWS_SESSION_TOKEN``, ``AWS_PROFILE``,
``AWS_ENDPOINT_URL`` / ``AWS_ENDPOINT_URL_S3`` (an S3-compatible server), ``AWS_REGION``, and
the files they name.

Everything that can go wrong before any work (the filesystem's package not installed, no
credentials, a store that cannot be reached, a bucket that does not exist) is one `StoreError`,
a ValueError whose message is one line naming the URI.

**Deadlines.** Every request to the store must be answered within a deadline, `TIMEOUT_S`
seconds unless the environment variable ``REFORM_SIM_STORE_TIMEOUT`` says otherwise (seconds, or
a duration such as ``90s``, ``2m``, ``500ms``): a store that accepts connections and never
answers is one `StoreError` naming the object, the operation and the deadline, never a wait
without end. A deadline that is not a duration, or is not above zero, is refused when the store
is opened, before any work.

fsspec is imported only inside these functions.
"""

from __future__ import annotations

import os
import re
from collections.abc import Callable, Iterator
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from datetime import datetime
from typing import Any

from reform.deadline import DURATION_FORM, DeadlineExpired, duration, in_thread

__all__ = [
    "TIMEOUT_S",
    "TIMEOUT_VARIABLE",
    "StoreError",
    "Store",
    "Upload",
    "is_uri",
    "open_store",
    "timeout",
]

TIMEOUT_S = 60.0  # seconds a store may take to answer one request, unless TIMEOUT_VARIABLE says
TIMEOUT_VARIABLE = "REFORM_SIM_STORE_TIMEOUT"
CHECK_ATTEMPTS = 2  # tries of the request that proves a store usable, before any work
_URI = re.compile(r"^[A-Za-z][A-Za-z0-9+.-]*://")
# The package each common scheme needs (fsspec's own registry knows the rest).
_PACKAGES = {"s3": "s3fs", "s3a": "s3fs", "gs": "gcsfs", "gcs": "gcsfs", "az": "adlfs"}
_CREDENTIALS = {
    "s3fs": "set AWS_ACCESS_KEY_ID and AWS_SECRET_ACCESS_KEY (or AWS_PROFILE) in the environment",
    "gcsfs": "set GOOGLE_APPLICATION_CREDENTIALS in the environment",
    "adlfs": "set AZURE_STORAGE_CONNECTION_STRING (or AZURE_STORAGE_ACCOUNT_NAME and "
    "AZURE_STORAGE_ACCOUNT_KEY) in the environment",
}


class StoreError(ValueError):
    """A store that cannot be used: one line naming the URI and what to do."""


def timeout(text: str | None = None) -> float:
    """The stores' deadline, seconds: ``text`` (a duration: ``30``, ``90s``, ``2m``, ``500ms``),
    by default the environment's ``REFORM_SIM_STORE_TIMEOUT``, else `TIMEOUT_S`.

    Raises:
        StoreError: not a duration, or not above zero (one line).
    """
    if text is None:
        text = os.environ.get(TIMEOUT_VARIABLE)
        if text is None or not text.strip():
            return TIMEOUT_S
    seconds = duration(text)
    if seconds is None:
        raise StoreError(f"{TIMEOUT_VARIABLE} must be {DURATION_FORM}, got {text!r}")
    return seconds


def is_uri(location: str | os.PathLike[str]) -> bool:
    """True for ``scheme://…`` (a store); False for a path on this machine."""
    return isinstance(location, str) and bool(_URI.match(location))


@dataclass(frozen=True)
class Upload:
    """A multipart upload begun and neither finished nor aborted: what a writer killed while it
    sent a large object in parts leaves (s3fs sends objects of 100 MiB and more so). It is no
    object (listings do not show it), but the store keeps its parts, and bills them, until it
    is aborted.

    Attributes:
        relative: the object's path, relative to the store's folder.
        upload_id: the store's ID of the upload.
        size: bytes of the parts sent, bytes.
        written: when it was begun or its last part was sent (timezone-aware).
    """

    relative: str
    upload_id: str
    size: int
    written: datetime


@dataclass(frozen=True)
class Store:
    """A folder in a filesystem (fsspec): paths relative to it, read and written whole.

    Attributes:
        uri: the folder's URI as given, without a trailing slash.
        fs: the fsspec filesystem.
        root: the folder's path in ``fs`` (the URI without its scheme).
    """

    uri: str
    fs: Any
    root: str
    timeout: float = TIMEOUT_S

    def url(self, relative: str = "") -> str:
        """The URI of ``relative`` (in messages and for other tools)."""
        return f"{self.uri}/{relative}" if relative else self.uri

    def path(self, relative: str) -> str:
        return f"{self.root}/{relative}" if relative else self.root

    def read(self, relative: str) -> bytes | None:
        """The object's bytes, or None when there is none."""
        self._forget(relative)
        try:
            return self._within("read", relative, self.fs.cat_file, self.path(relative))
        except FileNotFoundError:
            return None

    def read_many(self, relative: list[str]) -> dict[str, bytes | None]:
        """Several objects' bytes (None for one that is not there), fetched concurrently: one
        GET each."""
        if len(relative) <= 1:
            return {r: self.read(r) for r in relative}
        with ThreadPoolExecutor(max_workers=len(relative)) as pool:
            return dict(zip(relative, pool.map(self.read, relative), strict=True))

    def _within(self, what: str, relative: str, call: Callable[..., Any], *args, **kwargs) -> Any:
        """``call(*args, **kwargs)``, or a `StoreError` once the store has not answered within
        `timeout` seconds (the request is left to a thread that does not keep the process:
        `reform.deadline.in_thread`)."""
        try:
            return in_thread(self.timeout, call, *args, thread_name=f"store {what}", **kwargs)
        except DeadlineExpired:
            loop = getattr(self.fs, "loop", None)  # an async filesystem's (s3fs, gcsfs)
            if loop is not None:  # its abandoned requests fail as the process ends: not news
                loop.set_exception_handler(lambda loop, context: None)
            raise StoreError(
                f"{self.url(relative)}: the store did not answer within {self.timeout:g} s "
                f"({what}); check the store and the network, or give it longer with "
                f"{TIMEOUT_VARIABLE}=SECONDS"
            ) from None

    def _forget(self, relative: str) -> None:
        """Drops what the filesystem remembers of listings (another process may have written
        since)."""
        self.fs.invalidate_cache(self.path(relative))

    def write(self, relative: str, data: bytes) -> None:
        """Writes the object whole: in object storage it appears complete or not at all."""
        self._within("write", relative, self.fs.pipe_file, self.path(relative), data)

    def create(self, relative: str, data: bytes) -> bool:
        """Writes the object only if there is none (S3: a PUT with ``If-None-Match: *``);
        False when one is there."""

        def create() -> None:
            with self.fs.open(self.path(relative), "xb") as handle:
                handle.write(data)

        try:
            self._within("create", relative, create)
        except FileExistsError:
            return False
        return True

    def tag(self, relative: str) -> str | None:
        """The object's version tag (ETag), or None when the filesystem has none."""
        self._forget(relative)
        try:
            info = self._within("look up", relative, self.fs.info, self.path(relative))
        except FileNotFoundError:
            return None
        tag = info.get("ETag") or info.get("etag")
        return str(tag) if tag else None

    def replace(self, relative: str, data: bytes, tag: str) -> bool:
        """Overwrites the object only if it is still version ``tag`` (S3: ``If-Match``);
        False when another writer changed it first."""
        if type(self.fs).__name__ == "S3FileSystem":
            bucket, key, _ = self.fs.split_path(self.path(relative))
            try:
                put = self.fs.call_s3
                self._within(
                    "replace",
                    relative,
                    put,
                    "put_object",
                    Bucket=bucket,
                    Key=key,
                    Body=data,
                    IfMatch=tag,
                )
            except (OSError, FileExistsError):  # PreconditionFailed
                return False
            self.fs.invalidate_cache(self.path(relative))
            return True
        if self.tag(relative) != tag:
            return False
        self.write(relative, data)
        return True

    def delete(self, *relative: str) -> None:
        paths = [self.path(r) for r in relative]
        if paths:
            self._within("delete", relative[0], self.fs.rm, paths)

    def uploads(self, relative: str = "") -> list[Upload]:
        """The unfinished multipart uploads below ``relative`` (S3; none elsewhere: other
        filesystems' partial uploads are not listed), each with the bytes sent and when."""
        if type(self.fs).__name__ != "S3FileSystem":
            return []
        bucket, key, _ = self.fs.split_path(self.path(relative))
        _, root, _ = self.fs.split_path(self.root)
        found = []
        for upload in self._pages(
            "list uploads",
            relative,
            "list_multipart_uploads",
            "Uploads",
            ("KeyMarker", "UploadIdMarker"),
            Bucket=bucket,
            Prefix=f"{key.rstrip('/')}/" if key else "",
        ):
            size, written = 0, upload["Initiated"]
            for part in self._pages(
                "list parts",
                relative,
                "list_parts",
                "Parts",
                ("PartNumberMarker",),
                Bucket=bucket,
                Key=upload["Key"],
                UploadId=upload["UploadId"],
            ):
                size += int(part.get("Size", 0))
                written = max(written, part.get("LastModified", written))
            name = upload["Key"].removeprefix(f"{root}/") if root else upload["Key"]
            found.append(Upload(name, upload["UploadId"], size, written))
        return found

    def _pages(
        self,
        what: str,
        relative: str,
        method: str,
        field: str,
        markers: tuple[str, ...],
        **params: Any,
    ) -> Iterator[dict[str, Any]]:
        """The items (``field``) of every page of an S3 listing (``method``); ``markers``: the
        parameters whose ``Next…`` answers ask for the next page."""
        while True:
            page = self._within(what, relative, self.fs.call_s3, method, **params)
            yield from page.get(field, [])
            if not page.get("IsTruncated"):
                return
            params |= {m: page[f"Next{m}"] for m in markers if f"Next{m}" in page}

    def abort(self, *uploads: Upload) -> None:
        """Aborts unfinished multipart uploads (their parts are deleted); one already gone is
        not missed."""
        for upload in uploads:
            bucket, key, _ = self.fs.split_path(self.path(upload.relative))
            try:
                self._within(
                    "abort upload",
                    upload.relative,
                    self.fs.call_s3,
                    "abort_multipart_upload",
                    Bucket=bucket,
                    Key=key,
                    UploadId=upload.upload_id,
                )
            except FileNotFoundError:  # NoSuchUpload: finished or aborted meanwhile
                continue

    def sizes(self, relative: str = "") -> dict[str, int]:
        """Every object below ``relative``: its path relative to the folder -> bytes."""
        base = self.path(relative)
        self._forget(relative)
        try:
            found = self._within("list", relative, self.fs.find, base, detail=True)
        except FileNotFoundError:
            return {}
        prefix = self.root.rstrip("/") + "/"
        return {
            name.removeprefix(prefix): int(info.get("size") or 0)
            for name, info in found.items()
            if info.get("type", "file") != "directory"
        }


def open_store(uri: str, *, check: bool = True) -> Store:
    """The store at ``uri``; with ``check``, proven usable first: its filesystem installed,
    credentials found, the store reached, its bucket (first part of the path) there.

    Raises:
        StoreError: one line naming ``uri`` and what went wrong.
    """
    import fsspec

    deadline = timeout()
    uri = uri.rstrip("/")
    scheme = uri.split("://", 1)[0].lower()
    package = _PACKAGES.get(scheme)
    try:
        fs, root = fsspec.url_to_fs(uri)
    except (ImportError, ValueError) as exc:
        install = (
            "pip install 'reform-sim[s3]'"
            if package == "s3fs"
            else f"pip install {package}"
            if package
            else "install its fsspec filesystem"
        )
        raise StoreError(
            f"{uri}: cannot open a {scheme}:// store ({_first_line(exc)}); {install}"
        ) from None
    store = Store(uri=uri, fs=fs, root=root.rstrip("/"), timeout=deadline)
    if check:
        _check(store, scheme, package)
    return store


def _first_line(exc: BaseException) -> str:
    text = str(exc).strip().splitlines()
    return f"{type(exc).__name__}: {text[0]}" if text else type(exc).__name__


def _check(store: Store, scheme: str, package: str | None) -> None:
    """One listing of the bucket: the cheapest request that needs credentials, a reachable
    store and the bucket."""
    if scheme in ("memory", "file", "local"):
        return
    bucket = store.root.split("/", 1)[0]
    endpoint = _endpoint(store.fs)
    where = f" at {endpoint}" if endpoint else ""
    try:
        store._within("list", "", _checking(store.fs, scheme).ls, bucket, refresh=True)
    except StoreError:
        raise
    except FileNotFoundError:
        raise StoreError(
            f"{store.uri}: bucket {bucket!r} does not exist{where}; create it first or check "
            "the URI"
        ) from None
    except PermissionError as exc:
        raise StoreError(
            f"{store.uri}: access to bucket {bucket!r} denied{where} ({_first_line(exc)}); "
            f"check the credentials: {_CREDENTIALS.get(package or '', 'see its filesystem')}"
        ) from None
    except Exception as exc:  # noqa: BLE001 - every library has its own error classes
        name = type(exc).__name__
        if "Credentials" in name or "credentials" in str(exc).lower():
            raise StoreError(
                f"{store.uri}: no credentials for {scheme}://; "
                f"{_CREDENTIALS.get(package or '', 'see its filesystem')}"
            ) from None
        raise StoreError(
            f"{store.uri}: cannot reach the store{where} ({_first_line(exc)}); check the "
            "endpoint (AWS_ENDPOINT_URL for an S3-compatible server) and the network"
        ) from None


def _checking(fs: Any, scheme: str) -> Any:
    """The filesystem the check lists the bucket with: for S3, ``fs``'s own settings with
    botocore trying each request twice rather than five times (an endpoint nobody answers on
    is said in a second or two, not after eight of backing off); the run keeps ``fs``'s
    patience. Other filesystems are checked as they are."""
    if scheme not in ("s3", "s3a"):
        return fs
    import fsspec

    options = dict(getattr(fs, "storage_options", {}) or {})
    config = dict(options.get("config_kwargs") or {})
    config["retries"] = {"max_attempts": CHECK_ATTEMPTS, "mode": "standard"}
    return fsspec.filesystem(
        scheme, **{**options, "config_kwargs": config}, skip_instance_cache=True
    )


def _endpoint(fs: Any) -> str | None:
    """The S3 endpoint in use, when it is not AWS's own (for messages)."""
    endpoint = getattr(fs, "endpoint_url", None) or (getattr(fs, "client_kwargs", None) or {}).get(
        "endpoint_url"
    )
    return endpoint or os.environ.get("AWS_ENDPOINT_URL_S3") or os.environ.get("AWS_ENDPOINT_URL")
