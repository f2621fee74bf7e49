"""world/regular_file.py: the one bounded read of a file a user or a scene names."""
import os

import pytest

from world.regular_file import NotRegular, TooLarge, read_regular


def test_reads_a_regular_file_and_tells_its_size_before_the_read(tmp_path):
    p = tmp_path / "a.bin"
    p.write_bytes(b"12345")
    seen = []
    assert read_regular(p, 5, seen.append) == b"12345"
    assert seen == [5]


@pytest.mark.parametrize("kind", ["fifo", "folder", "device"])
def test_what_is_not_a_regular_file_is_refused_without_a_read(tmp_path, kind):
    p = {"fifo": tmp_path / "f", "folder": tmp_path, "device": "/dev/zero"}[kind]
    if kind == "fifo":
        os.mkfifo(p)                       # (no writer: a blocking open would hang)
    seen = []
    with pytest.raises(NotRegular):
        read_regular(p, 1 << 20, seen.append)
    assert seen == []


def test_a_file_over_the_cap_is_refused_by_its_size_before_the_read(tmp_path):
    p = tmp_path / "big"
    p.write_bytes(b"x" * 11)
    seen = []
    with pytest.raises(TooLarge) as e:
        read_regular(p, 10, seen.append)
    assert e.value.size == 11 and seen == []


def test_a_budget_that_refuses_stops_the_read_and_leaks_no_descriptor(tmp_path):
    p = tmp_path / "a"
    p.write_bytes(b"abc")
    before = len(os.listdir("/proc/self/fd"))

    def refuse(size):
        raise MemoryError(size)
    for _ in range(20):
        with pytest.raises(MemoryError):
            read_regular(p, 10, refuse)
    assert len(os.listdir("/proc/self/fd")) == before
