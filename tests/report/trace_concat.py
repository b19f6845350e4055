#!/usr/bin/python3
"""Joins traces into one of several frames, as a capture of several render passes is (each
frame keeps its own viewport): the header of the first (frame count and file size made new),
then every file's FRAM chunks in order (traces/FORMAT.md). Every input must be of the same
major version.

  trace_concat.py OUT.tvt IN1.tvt IN2.tvt ...
"""
import struct
import sys
from pathlib import Path


def split(data):
    """(header fields, chunks) of one trace file."""
    magic, major, minor, bom, size, frames, src_len = struct.unpack_from("<8sHHIQII", data, 0)
    if magic != b"\x89TVT\r\n\x1a\n" or size != len(data):
        raise SystemExit("trace_concat: not a trace file")
    head = 32 + src_len
    return (major, minor, bom, frames, data[32:head]), data[head:]


def concat(out, inputs):
    parts = [split(Path(p).read_bytes()) for p in inputs]
    majors = {p[0][0] for p in parts}
    if len(majors) != 1:
        raise SystemExit(f"trace_concat: traces of different majors {sorted(majors)}")
    (major, minor, bom, _, source), _ = parts[0]
    chunks = b"".join(c for _, c in parts)
    frames = sum(p[0][3] for p in parts)
    size = 32 + len(source) + len(chunks)
    Path(out).write_bytes(struct.pack("<8sHHIQII", b"\x89TVT\r\n\x1a\n", major, minor, bom, size, frames,
                                      len(source)) + source + chunks)


if __name__ == "__main__":
    if len(sys.argv) < 3:
        raise SystemExit(__doc__)
    concat(sys.argv[1], sys.argv[2:])
