"""A dataset folder in object storage (`reform.datasets.store`), read as one on disk is.

A ``reform-sim generate`` run writing to a store makes each shard part of the dataset in two
steps: the shard object is written whole (an object appears complete or not at all), then its
commit object, ``_commits/episode=<k>.json`` (its path, rows, frames, bytes and sha256), which
says it is done. The finished run writes the card listing every shard with its size and sha256
and deletes the commits. So a reader takes, from a finished dataset, the shards the card lists
(each checked against its size and sha256), and from an unfinished one (``allow_incomplete``)
the committed shards only (checked against their commits): a shard object no commit names (a
run writing it, or one killed while it did) is never read, and is said to be left out.
"""

from __future__ import annotations

import hashlib
from pathlib import PurePosixPath
from typing import Any

from reform.datasets._parquet_read import CARD_JSON, _json_object, _read_file, _read_folder
from reform.datasets.errors import DataFormatError
from reform.datasets.store import Store, open_store
from reform.frame import Dataset

__all__ = ["COMMITS_DIR", "StoreFolder", "commit_name", "read_store"]

COMMITS_DIR = "_commits"  # one object per finished shard while a run writes


def commit_name(episode: int) -> str:
    """The commit object of episode ``episode``'s shard, relative to the dataset."""
    return f"{COMMITS_DIR}/episode={int(episode)}.json"


class StoreFolder:
    """A dataset folder in a store, as `reform.datasets.parquet` reads folders: objects by
    relative path, listed once."""

    def __init__(self, store: Store) -> None:
        self.store = store
        self.name = PurePosixPath(store.root).name
        self.objects = store.sizes()
        self._contents: dict[str, bytes] = {}

    @classmethod
    def open(cls, uri: str) -> StoreFolder:
        return cls(open_store(uri))

    def where(self, relative: str = "") -> str:
        return self.store.url(relative)

    def card(self) -> dict[str, Any] | None:
        if CARD_JSON not in self.objects:
            return None
        text = self.store.read(CARD_JSON) or b""
        return _json_object(
            text, self.where(CARD_JSON), field=None, expected="a reform-sim dataset card (JSON)"
        )

    def parquet_files(self, what: str = "") -> list[str]:  # noqa: ARG002 (a store lists all)
        return [
            name
            for name in self.objects
            if name.endswith(".parquet")
            and not any(part.startswith((".", "_")) for part in PurePosixPath(name).parts)
        ]

    def size(self, relative: str) -> int | str:
        size = self.objects.get(relative)
        return "no such object" if size is None else size

    def _content(self, relative: str) -> bytes:
        if relative not in self._contents:
            content = self.store.read(relative)
            if content is None:
                raise OSError(f"{self.where(relative)}: no such object")
            self._contents[relative] = content
        return self._contents[relative]

    def sha256(self, relative: str) -> str:
        return hashlib.sha256(self._content(relative)).hexdigest()

    def read(self, relative: str) -> tuple[list, dict[str, Any]]:
        try:
            content = self._content(relative)
        except OSError as exc:
            raise DataFormatError(
                self.where(relative), None, None, "a Parquet file", str(exc)
            ) from None
        finally:
            self._contents.pop(relative, None)  # one shard held at a time
        return _read_file(self.where(relative), content)

    def commits(self) -> dict[int, dict[str, Any]]:
        """The commit objects: episode -> its entry (path, bytes, sha256, counts)."""
        out = {}
        for name in sorted(self.objects):
            if not (name.startswith(COMMITS_DIR + "/") and name.endswith(".json")):
                continue
            entry = _json_object(
                self.store.read(name) or b"",
                self.where(name),
                field=None,
                expected="a shard's commit (JSON)",
            )
            if not isinstance(entry.get("episode"), int) or not isinstance(entry.get("path"), str):
                raise DataFormatError(
                    self.where(name), None, "episode", "a shard's commit", repr(entry)[:80]
                )
            out[entry["episode"]] = entry
        return out

    def committed(self, card: Any) -> tuple[list[str], list[DataFormatError]]:
        """The shards an unfinished run has committed, each checked against its commit; every
        other shard object is a problem (left out, and said)."""
        keep: list[str] = []
        problems: list[DataFormatError] = []
        named: set[str] = set()
        for entry in self.commits().values():
            relative = entry["path"]
            named.add(relative)
            size = self.size(relative)
            if size != entry.get("bytes"):
                problems.append(
                    DataFormatError(
                        self.where(relative),
                        None,
                        "bytes",
                        f"{entry.get('bytes')} bytes (its commit {commit_name(entry['episode'])})",
                        f"{size}" if isinstance(size, str) else f"{size} bytes",
                    )
                )
                continue
            if self.sha256(relative) != entry.get("sha256"):
                problems.append(
                    DataFormatError(
                        self.where(relative),
                        None,
                        "sha256",
                        f"{entry.get('sha256')} (its commit)",
                        f"{self.sha256(relative)} (altered)",
                    )
                )
                continue
            keep.append(relative)
        for relative in sorted(set(self.parquet_files()) - named):
            problems.append(
                DataFormatError(
                    self.where(relative),
                    None,
                    None,
                    f"a shard committed in {COMMITS_DIR}/",
                    "a shard no commit names (being written, or left by a killed run)",
                )
            )
        return keep, problems


def read_store(uri: str, *, allow_incomplete: bool = False) -> Dataset:
    """`reform.datasets.read_parquet` of a URI: one ``.parquet`` object or a folder of them."""
    if uri.endswith(".parquet"):
        store = open_store(uri)
        content = store.read("")
        if content is None:
            raise DataFormatError(uri, None, None, "a Parquet file", "no such object")
        frames, header = _read_file(uri, content)
        return Dataset(
            frames=tuple(frames),
            name=str(header.get("name", PurePosixPath(store.root).stem)),
            source=str(header.get("source", "")),
            units="m",
            metadata=header.get("metadata", {}),
        )
    return _read_folder(StoreFolder.open(uri), allow_incomplete=allow_incomplete)
