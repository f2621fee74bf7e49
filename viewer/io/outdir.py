"""Folders hmblur writes into (compare --out, sweep --out, a video's folder of frames,
shot --buffers), under one rule: a file is written only where nothing is, or over a file
that hmblur wrote there and that has not changed since. Nothing else in the folder is
touched, so a folder that holds the user's own files never loses one.

What hmblur wrote is listed in the folder's MANIFEST: each file with its size and
modification time as written (a file edited or replaced since is the user's again), and
the subfolders it made whole (a sweep's cells/ and images/: every file in them is its
own, and only files of its own naming go there). The manifest changes in the same
imageio.OutputSet as the files it lists (written with them, renamed last). A manifest that
does not read as hmblur's is not hmblur's: the folder is refused until it is moved.
"""
from __future__ import annotations

import json
import os
import stat
from pathlib import Path

from world import limits
from world.errors import UserError

MANIFEST = ".hmblur-outputs.json"
KIND = "hmblur outputs"


class OutputFolder:
    """A folder a command writes into; `whole`: subfolders it makes and owns whole."""

    def __init__(self, path, flag: str, whole: tuple[str, ...] = ()):
        self.path, self.flag, self.whole = Path(path), flag, tuple(whole)

    # -- reading the manifest
    def manifest(self) -> dict:
        p = self.path / MANIFEST
        empty = {"kind": KIND, "files": {}, "folders": []}
        try:
            st = os.lstat(p)
        except FileNotFoundError:
            return empty
        except NotADirectoryError:
            return empty
        problem = None
        if not stat.S_ISREG(st.st_mode):
            problem = "is not a regular file"
        elif st.st_size > limits.MAX_OUTPUTS_MANIFEST_BYTES:
            problem = f"holds more than {limits.MAX_OUTPUTS_MANIFEST_BYTES} bytes"
        else:
            try:
                doc = json.loads(p.read_bytes().decode("utf-8"))
            except (OSError, ValueError, RecursionError):
                doc = None
            if _valid(doc):
                return doc
            problem = "does not read as hmblur's list of its files"
        raise UserError(f"{self.flag} {self.path}: {p.name} {problem}: hmblur keeps the list "
                        "of the files it wrote there under that name; move that file away")

    def _owned_whole(self, rel: str) -> str | None:
        """The whole subfolder `rel` lies in, if any of this folder's."""
        top = rel.split("/", 1)[0]
        return top if "/" in rel and top in self.whole else None

    def _problem(self, rel: str, doc: dict) -> str | None:
        """Why hmblur may not write `rel` (None: it may)."""
        p = self.path / rel
        folder = self._owned_whole(rel)
        if folder is not None:
            f = self.path / folder
            if os.path.lexists(f) and (folder not in doc["folders"] or f.is_symlink()
                                       or not f.is_dir()):
                return f"{folder}/"
            return None
        if not os.path.lexists(p):
            return None
        rec = doc["files"].get(rel)
        try:
            st = os.lstat(p)
        except OSError:
            return rel
        if rec is None or not stat.S_ISREG(st.st_mode) or [st.st_size, st.st_mtime_ns] != rec:
            return rel
        return None

    def check(self, names=(), folders=()):
        """Before any work: every relative name it will write, and every whole subfolder
        it will use, may be written (else one line naming up to three of them)."""
        doc = self.manifest()
        clash = [x for x in dict.fromkeys([self._problem(n, doc) for n in names]
                                          + [self._problem(f"{f}/x", doc) for f in folders])
                 if x is not None]
        if clash:
            more = f" and {len(clash) - 3} more" if len(clash) > 3 else ""
            raise UserError(f"{self.flag} {self.path}: holds {', '.join(clash[:3])}{more}, "
                            "which hmblur did not write (or which changed since it did) and "
                            "this run would replace: give an empty or new folder, or move "
                            "them")

    # -- OutputSet's side (imageio.OutputSet(folder=...))
    def rel(self, path: Path) -> str | None:
        """`path` relative to this folder (posix), or None when it lies outside."""
        try:
            r = Path(path).relative_to(self.path)
        except ValueError:
            return None
        return r.as_posix() if r.parts else None

    def before(self, paths) -> dict:
        """The manifest now, after checking each path of a commit (one line if one may
        not be written)."""
        doc = self.manifest()
        rels = [r for r in (self.rel(p) for p in paths) if r is not None]
        clash = [x for x in dict.fromkeys(self._problem(r, doc) for r in rels) if x]
        if clash:
            more = f" and {len(clash) - 3} more" if len(clash) > 3 else ""
            raise UserError(f"{self.flag} {self.path}: {', '.join(clash[:3])}{more} changed or "
                            "appeared while hmblur ran, and hmblur did not write it: nothing "
                            "was replaced; move it and run again")
        return doc

    def after(self, doc: dict, written: list[tuple[Path, Path]], removed: list[str]) -> bytes | None:
        """The manifest once `written` ((temp file, destination), ...) are renamed and the
        `removed` names unlinked, as bytes; None when it does not change."""
        files = dict(doc["files"])
        folders = list(doc["folders"])
        for tmp, dest in written:
            r = self.rel(dest)
            if r is None or r == MANIFEST:
                continue
            folder = self._owned_whole(r)
            if folder is not None:
                if folder not in folders:
                    folders.append(folder)
                continue
            st = os.stat(tmp)               # (a rename keeps the size and the mtime)
            files[r] = [st.st_size, st.st_mtime_ns]
        for r in removed:
            files.pop(r, None)
        new = {"kind": KIND, "files": dict(sorted(files.items())), "folders": sorted(folders)}
        if new == doc:
            return None
        return (json.dumps(new, indent=1, sort_keys=True) + "\n").encode("utf-8")

    def owned_files(self) -> list[str]:
        """The names hmblur wrote here that are still as it wrote them."""
        doc = self.manifest()
        return [r for r in doc["files"] if self._problem(r, doc) is None
                and os.path.lexists(self.path / r)]


def _valid(doc) -> bool:
    if not (isinstance(doc, dict) and doc.get("kind") == KIND
            and isinstance(doc.get("files"), dict) and isinstance(doc.get("folders"), list)):
        return False
    for r, rec in doc["files"].items():
        if not (_safe(r) and isinstance(rec, list) and len(rec) == 2
                and all(isinstance(x, int) and not isinstance(x, bool) for x in rec)):
            return False
    return all(isinstance(f, str) and _safe(f) and "/" not in f for f in doc["folders"])


def _safe(rel: str) -> bool:
    """A name inside the folder (a manifest cannot make hmblur write elsewhere)."""
    parts = rel.split("/")
    return bool(rel) and not rel.startswith("/") and all(p not in ("", ".", "..") for p in parts)
