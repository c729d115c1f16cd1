#!/usr/bin/env python3
"""Checks the virtual board's poses against the host's tracker.

usage: compare_poses.py CONSOLE.log FRAMES.y4m OUT_DIR

The board printed its pose lines (with --frame-crc) between '=== poses ===' and
'=== end poses ==='. Each line's luma CRC names the recorded frame it tracked
(the camera shows a frame one or more times). This writes OUT_DIR/as_captured.y4m,
the recording's frames in the order the board tracked them, and OUT_DIR/board.csv,
the board's poses in `gabarit track`'s columns, for the caller to compare with
`gabarit track` on the host. Lines after the recording's last frame (the camera
outputting something else once the feed stopped) are dropped. Fails if a tracked
frame is not in the recording, or a recorded frame never reached the board.
"""
import pathlib
import sys
import zlib


def read_y4m(path):
    data = pathlib.Path(path).read_bytes()
    header, _, rest = data.partition(b"\n")
    fields = {f[:1]: f[1:] for f in header.split()[1:]}
    w, h = int(fields[b"W"]), int(fields[b"H"])
    chroma = {b"mono": 0, b"420jpeg": w * h // 2, b"420": w * h // 2, b"420mpeg2": w * h // 2}
    extra = chroma.get(fields.get(b"C", b"420jpeg"), w * h // 2)
    frames = []
    while rest:
        marker, _, rest = rest.partition(b"\n")
        assert marker.startswith(b"FRAME"), "bad Y4M frame marker"
        frames.append(rest[: w * h])
        rest = rest[w * h + extra:]
    return header, w, h, frames


def main():
    if len(sys.argv) != 4:
        print(__doc__, file=sys.stderr)
        return 2
    console, frames_path, out = sys.argv[1], sys.argv[2], pathlib.Path(sys.argv[3])
    lines = pathlib.Path(console).read_text(errors="replace").splitlines()
    try:
        start = next(i for i, l in enumerate(lines) if l.strip() == "=== poses ===")
        end = next(i for i, l in enumerate(lines) if l.strip() == "=== end poses ===")
    except StopIteration:
        print("FAIL: the console has no pose block")
        return 1
    rows = [l.strip() for l in lines[start + 2:end] if l.strip()]
    _, w, h, frames = read_y4m(frames_path)
    index_of = {}
    for i, f in enumerate(frames):
        index_of.setdefault(f"{zlib.crc32(f) & 0xffffffff:08x}", i)
    order = []
    for row in rows:
        crc = row.split(",")[-1]
        order.append(index_of.get(crc))
    while order and order[-1] is None:
        order.pop()
    rows = rows[: len(order)]
    if not order:
        print("FAIL: no tracked frame matches the recording")
        return 1
    if None in order:
        bad = order.index(None)
        print(f"FAIL: tracked frame {bad} (CRC {rows[bad].split(',')[-1]}) is not a frame of the recording")
        return 1
    missing = sorted(set(range(len(frames))) - set(order))
    if missing:
        print(f"FAIL: recorded frames never tracked: {missing[:10]}")
        return 1
    if any(b < a for a, b in zip(order, order[1:])):
        print("FAIL: frames arrived out of order")
        return 1
    out.mkdir(parents=True, exist_ok=True)
    with open(out / "as_captured.y4m", "wb") as y4m:
        y4m.write(f"YUV4MPEG2 W{w} H{h} F30:1 Ip A1:1 Cmono\n".encode())
        for i in order:
            y4m.write(b"FRAME\n" + frames[i])
    header = "frame,x,y,theta_deg,depth,votes,score,status"
    (out / "board.csv").write_text(header + "\n" + "".join(",".join(r.split(",")[:8]) + "\n" for r in rows))
    print(f"{len(rows)} tracked frames map onto all {len(frames)} recorded frames, in order "
          f"({len(rows) - len(frames)} repeats)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
