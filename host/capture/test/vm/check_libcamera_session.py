#!/usr/bin/env python3
"""Checks the session folder `flutterscan scan --camera libcamera:ID --frames N` wrote in the
libcamera vimc guest (run_libcamera_vimc_vm.sh): N frames captured and logged, camera sequence
numbers one apart, camera timestamps increasing at a plausible frame interval, nothing lost or
failed on the camera's side, and the kept frames full-size pictures that are not uniform.

Usage: check_libcamera_session.py SESSION_DIR FRAMES
Prints what it checked; exit 0 pass, 1 fail."""

import json
import struct
import sys
import zlib
from pathlib import Path


def png_size_and_spread(path):
    """Width, height, bit depth and (min, max) of the first channel of a PNG frame."""
    data = path.read_bytes()
    if data[:8] != b"\x89PNG\r\n\x1a\n":
        raise ValueError(f"{path.name} is not a PNG")
    pos, idat, header = 8, b"", None
    while pos < len(data):
        length, kind = struct.unpack(">I4s", data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + length]
        if kind == b"IHDR":
            header = struct.unpack(">IIBBBBB", body)
        elif kind == b"IDAT":
            idat += body
        pos += 12 + length
    width, height, depth, colour, _, _, interlace = header
    if interlace:
        raise ValueError(f"{path.name}: interlaced PNG")
    channels = {0: 1, 2: 3, 4: 2, 6: 4}[colour]
    bpp = channels * depth // 8
    stride = width * bpp
    raw = zlib.decompress(idat)
    rows, previous = [], bytearray(stride)
    for y in range(height):
        kind = raw[y * (stride + 1)]
        line = bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        for i in range(stride):
            a = line[i - bpp] if i >= bpp else 0
            b = previous[i]
            c = previous[i - bpp] if i >= bpp else 0
            if kind == 1:
                line[i] = (line[i] + a) & 0xFF
            elif kind == 2:
                line[i] = (line[i] + b) & 0xFF
            elif kind == 3:
                line[i] = (line[i] + (a + b) // 2) & 0xFF
            elif kind == 4:
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                line[i] = (line[i] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 0xFF
        rows.append(bytes(line))
        previous = line
    step = depth // 8
    values = [int.from_bytes(row[i:i + step], "big") for row in rows[::7]
              for i in range(0, stride, bpp * 5)]
    return width, height, depth, min(values), max(values)


def main():
    session, frames = Path(sys.argv[1]), int(sys.argv[2])
    problems = []
    lines = [json.loads(l) for l in (session / "session.jsonl").read_text().splitlines() if l]
    frame_lines = [l for l in lines if "index" in l and "sequence" in l]
    print(f"check: {len(frame_lines)} frame lines in session.jsonl")
    if len(frame_lines) != frames:
        problems.append(f"{len(frame_lines)} frames logged, {frames} asked for")
    sequences = [l["sequence"] for l in frame_lines]
    stamps = [l["camera_ns"] for l in frame_lines]
    print(f"check: sequences {sequences}")
    if any(b - a != 1 for a, b in zip(sequences, sequences[1:])):
        problems.append(f"sequence numbers not one apart: {sequences}")
    intervals = [(b - a) / 1e6 for a, b in zip(stamps, stamps[1:])]
    print("check: camera timestamp steps, ms: " + " ".join(f"{i:.1f}" for i in intervals))
    if any(i <= 0 for i in intervals):
        problems.append(f"camera timestamps not increasing: {stamps}")
    elif intervals and not all(1 <= i <= 2000 for i in intervals):
        problems.append(f"camera timestamp steps outside 1..2000 ms: {intervals}")
    for l in frame_lines:
        if "error" in l or "error" in l.get("flags", []):
            problems.append(f"frame {l['sequence']}: {l.get('error', 'flagged error')}")

    summary = json.loads((session / "summary.json").read_text())
    keys = ("frames_captured", "frames_processed", "frames_dropped", "frames_failed",
            "camera_frames_lost", "stopped_by")
    print("check: summary " + ", ".join(f"{k}={summary.get(k)}" for k in keys))
    if summary.get("frames_captured") != frames:
        problems.append(f"summary.json: frames_captured {summary.get('frames_captured')}")
    for key in ("camera_frames_lost", "frames_failed"):
        if summary.get(key):
            problems.append(f"summary.json: {key} {summary[key]}")

    pngs = sorted(p for p in (session / "frames").glob("f*.png") if ".fused" not in p.name)
    if not pngs:
        problems.append("no frame kept in frames/")
    for png in pngs[:2]:
        width, height, depth, low, high = png_size_and_spread(png)
        descriptor = json.loads(png.with_suffix(".json").read_text())
        print(f"check: {png.name} {width}x{height} {depth}-bit, values {low}..{high}; "
              f"capture {descriptor.get('capture')}")
        if high - low < 16:
            problems.append(f"{png.name} is uniform (values {low}..{high})")

    for p in problems:
        print(f"check: FAIL {p}")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
