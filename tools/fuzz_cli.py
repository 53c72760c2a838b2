#!/usr/bin/env python3
"""Mutation fuzzing of the samp command line (docs/reliability.md).

Runs a samp command line on N mutants of one input file and checks each run:
exit status 0 or 1 (1 = samp's one-line "samp: error: ..."), never a signal,
exit 2 (a usage error, which these runs never make), "samp: error: internal
error" (an exception other than samp::Error), a sanitizer report, a timeout or
more peak memory than --max-rss-mb. Mutations (seeded): flipped bits, random
bytes, runs overwritten, cut files, inserted and deleted bytes, edited
decimal numbers (grid dims, counts, header fields), extreme little-endian
integers, and for text inputs tokens replaced by nan/inf/huge/negative
values, fields dropped and lines repeated. Findings are copied to
--findings. Prints a summary line and exits 1 on any finding.

Two ways to place the mutant:
  * a single file (--input; --model is the old name): {} in the command is
    the mutant's path (its suffix kept: .vdb, .ply, .off, .obj, ...);
  * a file inside a folder (--template DIR --target RELATIVE_PATH): each run
    copies DIR, replaces RELATIVE_PATH by the mutant; {} is the copy, {out} a
    fresh output folder beside it (a sequence's calib, detections, poses,
    planes, image or disparity PNG under `samp fit`; a mesh among good ones
    under `samp train`).

With --reseal (model files) each mutant's samp_file_bytes and
samp_file_checksum are recomputed (when its file metadata still parses), as
somebody editing a file on purpose would, so that the mutants reach samp's
payload decoder instead of failing the checksum.

  python3 tools/fuzz_cli.py --samp build/tools/samp/samp --input models/samp_cars_r5.vdb \
      --runs 20000 --jobs 2 --work /tmp/samp_fuzz_cli
  python3 tools/fuzz_cli.py --samp build/tools/samp/samp --template SEQ --target calib/000046.txt \
      --runs 500 -- fit --seq {} --out {out} --no-meshes -q
"""
import argparse
import os
import random
import re
import shutil
import struct
import subprocess
import sys
import tempfile
import time
from concurrent.futures import ThreadPoolExecutor


def mutate(data: bytes, rng: random.Random) -> bytes:
    b = bytearray(data)
    if not b:
        return bytes(rng.randrange(256) for _ in range(rng.randint(0, 64)))
    kind = rng.randrange(8)
    if kind == 0:  # flip 1-8 bits
        for _ in range(rng.randint(1, 8)):
            i = rng.randrange(len(b))
            b[i] ^= 1 << rng.randrange(8)
    elif kind == 1:  # random bytes
        for _ in range(rng.randint(1, 16)):
            b[rng.randrange(len(b))] = rng.randrange(256)
    elif kind == 2:  # overwrite a run with one value
        i = rng.randrange(len(b))
        n = rng.randint(1, 4096)
        v = rng.choice([0, 0xFF, 0x7F, 0x80, rng.randrange(256)])
        b[i:i + n] = bytes([v]) * len(b[i:i + n])
    elif kind == 3:  # cut
        b = b[:rng.randrange(len(b))]
    elif kind == 4:  # insert bytes
        i = rng.randrange(len(b))
        b[i:i] = bytes(rng.randrange(256) for _ in range(rng.randint(1, 64)))
    elif kind == 5:  # delete bytes
        i = rng.randrange(len(b))
        del b[i:i + rng.randint(1, 64)]
    elif kind == 6:  # edit a decimal number in the metadata (dims, counts, R)
        text = bytes(b[:4096])
        numbers = [m for m in re.finditer(rb"\d+", text)]
        if numbers:
            m = rng.choice(numbers)
            new = str(rng.choice([0, 1, 2, 1200, 65535, 2**31 - 1, 2**32, 10**12,
                                  int(m.group()) + 1])).encode()
            if rng.random() < 0.5:  # keep the length when possible
                new = new[:len(m.group())].rjust(len(m.group()), b"0")
            b[m.start():m.end()] = new
    elif kind == 7 and is_text(data):  # a token replaced, a field dropped or a line repeated
        lines = bytes(b).split(b"\n")
        k = rng.randrange(len(lines))
        fields = lines[k].split(b" ")
        action = rng.randrange(3)
        if action == 0:
            fields[rng.randrange(len(fields))] = rng.choice(
                [b"nan", b"-nan", b"inf", b"-inf", b"1e308", b"-1e308", b"-1", b"0", b"2147483648",
                 b"99999999999999999999", b"", b"x"])
        elif action == 1 and len(fields) > 1:
            del fields[rng.randrange(len(fields))]
        else:
            lines[k:k] = [lines[k]] * rng.randint(1, 3)
        lines[k] = b" ".join(fields)
        return b"\n".join(lines)
    else:  # a 4- or 8-byte little-endian integer set to an extreme
        i = rng.randrange(max(1, len(b) - 8))
        width = rng.choice([4, 8])
        v = rng.choice([0, 1, 2**31 - 1, 2**31, 2**32 - 1, 2**63 - 1, 2**63, 2**64 - 1])
        b[i:i + width] = (v % (1 << (8 * width))).to_bytes(width, "little")
    return bytes(b)


def is_text(data: bytes) -> bool:
    head = data[:4096]
    return bool(head) and all(c in b"\t\n\r" or 32 <= c < 127 for c in head)


def reseal(data: bytes) -> bytes:
    """Recomputes samp_file_bytes and samp_file_checksum (FNV-1a 64 over every
    byte, the two values read as '0'); returns `data` unchanged when its header
    or file metadata does not parse (docs/model_format.md, "File metadata")."""
    b = bytearray(data)
    pos = 8 + 4 + 4 + 4 + 1 + 36  # magic, file version, library version, offsets flag, UUID

    def read(fmt):
        nonlocal pos
        size = struct.calcsize("<" + fmt)
        if pos + size > len(b):
            raise ValueError("truncated")
        value = struct.unpack_from("<" + fmt, b, pos)[0]
        pos += size
        return value

    try:
        values = {}
        for _ in range(min(read("i"), 4096)):
            name_size = read("I")
            name = bytes(b[pos:pos + name_size])
            pos += name_size
            type_size = read("I")  # (not `pos += read(...)`: read moves pos)
            pos += type_size
            size = read("I")
            values[name] = (pos, size)
            pos += size
        size_at, size_len = values[b"samp_file_bytes"]
        sum_at, sum_len = values[b"samp_file_checksum"]
    except (ValueError, KeyError, struct.error):
        return data
    if size_len != 20 or sum_len != 16 or max(size_at + 20, sum_at + 16) > len(b):
        return data
    b[size_at:size_at + 20] = b"%020d" % len(b)
    blank = bytearray(b)
    blank[size_at:size_at + 20] = b"0" * 20
    blank[sum_at:sum_at + 16] = b"0" * 16
    h = 0xCBF29CE484222325
    for c in blank:
        h = ((h ^ c) * 0x100000001B3) & 0xFFFFFFFFFFFFFFFF
    b[sum_at:sum_at + 16] = b"%016x" % h
    return bytes(b)


def run_one(args, index, data, work):
    rng = random.Random(args.seed * 1000003 + index)
    mutant = mutate(data, rng)
    if args.reseal:
        mutant = reseal(mutant)
    out = os.path.join(work, f"out_{index}")
    if args.template:
        place = os.path.join(work, f"run_{index}")
        shutil.copytree(args.template, place)
        path = os.path.join(place, args.target)
    else:
        place = os.path.join(work, f"mutant_{index}{os.path.splitext(args.input)[1]}")
        path = place
    with open(path, "wb") as f:
        f.write(mutant)
    command = [part.replace("{out}", out).replace("{}", place) for part in args.command]
    start = time.time()
    proc = subprocess.Popen([args.samp] + command, stdout=subprocess.DEVNULL,
                            stderr=subprocess.PIPE)
    try:
        _, err = proc.communicate(timeout=args.timeout)
        timed_out = False
    except subprocess.TimeoutExpired:
        proc.kill()
        _, err = proc.communicate()
        timed_out = True
    # ru_maxrss of the child (kB) via /proc is gone after exit; wait4 gave it to Popen.
    rss_mb = getattr(proc, "rss_kb", 0) / 1024.0
    err = err.decode("utf-8", "replace")
    # Warnings and per-sequence errors may come first; samp's verdict is the last line.
    lines = err.strip().splitlines()
    last_line = lines[-1] if lines else ""
    finding = None
    if timed_out:
        finding = "timeout"
    elif proc.returncode < 0:
        finding = f"signal {-proc.returncode}"
    elif proc.returncode not in (0, 1):
        finding = f"exit {proc.returncode}"
    elif "Sanitizer" in err or "runtime error:" in err:
        finding = "sanitizer report"
    elif proc.returncode == 1 and not last_line.startswith("samp: error: "):
        finding = "error without samp's one-line message (last line of stderr)"
    elif proc.returncode == 1 and last_line.startswith("samp: error: internal error"):
        finding = "internal error (an exception other than samp::Error)"
    elif rss_mb > args.max_rss_mb:
        finding = f"peak RSS {rss_mb:.0f} MB"
    if finding:
        os.makedirs(args.findings, exist_ok=True)
        shutil.copy(path, os.path.join(args.findings, f"finding_{index}{os.path.splitext(path)[1]}"))
        with open(os.path.join(args.findings, f"finding_{index}.txt"), "w") as f:
            f.write(f"{finding}\n{' '.join(command)}\n{err}\n")
    shutil.rmtree(out, ignore_errors=True)
    if args.template:
        shutil.rmtree(place, ignore_errors=True)
    else:
        os.remove(place)
    return proc.returncode, finding, rss_mb, time.time() - start


class RusagePopen(subprocess.Popen):
    """Popen that records the child's peak RSS from wait4."""

    def _try_wait(self, wait_flags):
        try:
            pid, status, usage = os.wait4(self.pid, wait_flags)
        except ChildProcessError:
            pid, status = self.pid, 0
            usage = None
        if pid == self.pid and usage is not None:
            self.rss_kb = usage.ru_maxrss
        return (pid, status)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--samp", required=True, help="the samp executable")
    parser.add_argument("--input", "--model", dest="input", help="the file to mutate (alone, or --target's original)")
    parser.add_argument("--template", help="a folder copied for each run; the mutant replaces its --target")
    parser.add_argument("--target", help="with --template: the file (relative path) to mutate")
    parser.add_argument("--runs", type=int, default=1000)
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--timeout", type=float, default=120.0, help="seconds per run")
    parser.add_argument("--max-rss-mb", type=float, default=1024.0)
    parser.add_argument("--work", default=None, help="folder for the mutants (default: a temporary one)")
    parser.add_argument("--findings", default="fuzz_cli_findings")
    parser.add_argument("--reseal", action="store_true",
                        help="recompute each mutant's file size and checksum (mutants reach the decoder)")
    parser.add_argument("command", nargs="*", default=["inspect", "{}"],
                        help="samp arguments, {} = the mutant (default: inspect {})")
    args = parser.parse_args()
    if bool(args.template) != bool(args.target):
        parser.error("--template and --target go together")
    if args.template and not args.input:
        args.input = os.path.join(args.template, args.target)
    if not args.input:
        parser.error("give --input FILE or --template DIR --target FILE")
    subprocess.Popen = RusagePopen
    with open(args.input, "rb") as f:
        data = f.read()
    work = args.work or tempfile.mkdtemp(prefix="samp_fuzz_cli_")
    os.makedirs(work, exist_ok=True)
    counts = {}
    findings = 0
    peak = 0.0
    start = time.time()
    with ThreadPoolExecutor(max_workers=args.jobs) as pool:
        for code, finding, rss, _ in pool.map(lambda i: run_one(args, i, data, work), range(args.runs)):
            counts[code] = counts.get(code, 0) + 1
            peak = max(peak, rss)
            if finding:
                findings += 1
                print(f"finding: {finding}", file=sys.stderr)
    print(f"fuzz_cli: {args.runs} runs of samp {' '.join(args.command)} in {time.time() - start:.0f} s, "
          f"exit codes {dict(sorted(counts.items()))}, peak RSS {peak:.0f} MB, {findings} findings")
    return 1 if findings else 0


if __name__ == "__main__":
    sys.exit(main())
