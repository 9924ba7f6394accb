#!/usr/bin/env python3
"""Reference sender of the remote person detector's datagrams (docs/people.md).

Replays a recorded box file to the robot over UDP, one datagram per frame, as a detector on
another computer would: each frame's capture time is the moment it is sent (minus --latency),
and the sequence number counts up from --first-sequence.

Box file: one JSON object per line,
    {"t_s": 0.10, "boxes": [[u0, v0, u1, v1, confidence, class], ...]}
frames in time order; t_s paces the replay (--rate scales it). Blank lines and lines
starting with '#' are skipped.

    tools/detector_replay.py --to 192.168.1.20:5600 boxes.jsonl
"""
import argparse
import json
import socket
import struct
import sys
import time
import zlib

VERSION = 1
MAX_BOXES = 16


def datagram(source, sequence, capture_unix_ns, width, height, boxes):
    if len(boxes) > MAX_BOXES:
        raise ValueError("at most %d boxes per frame" % MAX_BOXES)
    body = struct.pack("<4sBBHIIqHH", b"S3PD", VERSION, 0, len(boxes), source, sequence & 0xFFFFFFFF,
                       capture_unix_ns, width, height)
    for u0, v0, u1, v1, confidence, cls in boxes:
        body += struct.pack("<HHHHHH", round(u0), round(v0), round(u1), round(v1), round(confidence * 10000), cls)
    return body + struct.pack("<I", zlib.crc32(body) & 0xFFFFFFFF)


def read_frames(path):
    frames = []
    with open(path) as f:
        for number, line in enumerate(f, 1):
            line = line.strip()
            if not line or line.startswith("#"):
                continue
            try:
                frame = json.loads(line)
                t = float(frame["t_s"])
                boxes = [tuple(b) for b in frame["boxes"]]
                for b in boxes:
                    if len(b) != 6:
                        raise ValueError("a box is [u0, v0, u1, v1, confidence, class]")
            except (ValueError, KeyError, TypeError) as e:
                sys.exit("%s:%d: %s" % (path, number, e))
            frames.append((t, boxes))
    return frames


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("boxes", help="the box file (JSON lines)")
    p.add_argument("--to", required=True, help="HOST:PORT of the robot's detection port")
    p.add_argument("--source", type=int, default=1, help="this detector's id (default 1)")
    p.add_argument("--first-sequence", type=int, default=1)
    p.add_argument("--width", type=int, default=1280)
    p.add_argument("--height", type=int, default=720)
    p.add_argument("--latency", type=float, default=0.0, help="seconds the detection took: capture = now - latency")
    p.add_argument("--rate", type=float, default=1.0, help="replay speed (2: twice as fast)")
    args = p.parse_args()
    host, _, port = args.to.rpartition(":")
    if not host or not port.isdigit():
        sys.exit("--to: expected HOST:PORT, got %r" % args.to)
    frames = read_frames(args.boxes)
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    start = time.monotonic()
    t0 = frames[0][0] if frames else 0.0
    for i, (t, boxes) in enumerate(frames):
        delay = start + (t - t0) / args.rate - time.monotonic()
        if delay > 0:
            time.sleep(delay)
        capture = time.time_ns() - int(args.latency * 1e9)
        sock.sendto(datagram(args.source, args.first_sequence + i, capture, args.width, args.height, boxes),
                    (host, int(port)))
    print("sent %d frames" % len(frames), file=sys.stderr)


if __name__ == "__main__":
    main()
