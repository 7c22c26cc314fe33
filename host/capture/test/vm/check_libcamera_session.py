#!/usr/bin/env python3
"""Checks the session folder `flutterscan scan --camera libcamera:ID --frames N` wrote in the
libcamera vimc guest (run_libcamera_vimc_vm.sh): N frames captured and logged at the size asked
for, camera sequence numbers one apart, camera timestamps increasing at a plausible frame
interval, nothing lost by the camera, no frame failed. (No frame is processed: the sim controller
sees no strobe from a real camera, so no exposure event matches a frame; libcamera_vimc_check
checks the pixels.)

Usage: check_libcamera_session.py SESSION_DIR FRAMES WIDTH HEIGHT
Prints what it checked; exit 0 pass, 1 fail."""

import json
import sys
from pathlib import Path


def main():
    session, frames = Path(sys.argv[1]), int(sys.argv[2])
    width, height = int(sys.argv[3]), int(sys.argv[4])
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
    keys = ("frame_size", "frames_captured", "frames_processed", "frames_without_event",
            "frames_failed", "camera_frames_lost", "stopped_by")
    print("check: summary " + ", ".join(f"{k}={summary.get(k)}" for k in keys))
    if summary.get("frames_captured") != frames:
        problems.append(f"summary.json: frames_captured {summary.get('frames_captured')}")
    if not str(summary.get("frame_size", "")).startswith(f"{width}x{height} "):
        problems.append(f"summary.json: frame_size {summary.get('frame_size')}, "
                        f"{width}x{height} asked for")
    for key in ("camera_frames_lost", "frames_failed"):
        if summary.get(key):
            problems.append(f"summary.json: {key} {summary[key]}")
    if summary.get("stopped_by") != "max_frames":
        problems.append(f"summary.json: stopped_by {summary.get('stopped_by')}")

    for p in problems:
        print(f"check: FAIL {p}")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
