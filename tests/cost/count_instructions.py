#!/usr/bin/env python3
"""Exact instruction counts per stage of the frame path, from qemu-user's own logs.

Debian 12's qemu-user (7.2) has no TCG plugin to count instructions, but it logs every
translated block with its guest instructions (-d in_asm) and, with block chaining off
(-d nochain), every execution of a block (-d exec: a "Trace" line naming the block's host
address). Instructions = sum over executions of the block's instruction count: exact for
code that runs to the end of its blocks (a block cut short by a signal would be counted
whole; the frame path raises none). The same method on x86-64 (qemu-x86_64) gives the
comparison. A stage's cost is (count at 2R repetitions - count at R) / R: the set-up (lens
table, SH tables, the route) cancels. See docs/BENCHMARKS.md, "ARM cost, measured".

  tests/cost/count_instructions.py --arch aarch64 --binary build/cost-aarch64/tests/cost/stage_cost \
      --sysroot build/sysroot-arm64 [--repetitions 4] [--functions 8] [CASE ...]

A CASE is STAGE[:ROUTE_FRAMES[:STORAGE]] (stage_cost's arguments; STORAGE as [capacities]
route_storage: float32, bfloat16, codes8 or codes16; STAGE may carry stage_cost's @BANDS and
+wWfF, the route filter's search window, e.g. frame+w128f10:100000:float32); without any,
the default list below.
Prints one line per case: instructions per repetition, and with --functions N the N
functions with the most instructions per repetition (self counts).
"""
import argparse
import collections
import os
import re
import subprocess
import sys
import tempfile

DEFAULT_CASES = [
    "segmentation", "descriptor", "strip", "correlation", "heading",
    "filter:1000", "filter:1000:bfloat16", "filter:10000", "filter:10000:bfloat16",
    "filter:100000", "filter:100000:bfloat16",
    "frame:10000", "frame:10000:bfloat16", "frame:100000:bfloat16",
]

# The cost model (a model, not a measurement; docs/BENCHMARKS.md, "ARM cost, measured",
# gives the sources): time = instructions / (IPC x clock), except the route scan (the
# functions named in SCAN_FUNCTIONS), which takes at least its bytes / memory bandwidth
# when the route does not fit in L2 (512 KiB on the Pi 3's BCM2837, 1 MiB on the Pi 4's
# BCM2711): from about 2,000 (float) or 3,500 (bfloat16) frames of 64 bands up. IPC is a range: a low and a high assumption under
# the core's issue width (Cortex-A53: 2, in order; Cortex-A72: 3, out of order).
CORES = [
    # name, clock Hz, IPC low, IPC high, sustained single-core bandwidth bytes/s, L2 bytes
    ("A53@1.2GHz", 1.2e9, 0.7, 1.0, 2.0e9, 512 << 10),
    ("A72@1.5GHz", 1.5e9, 1.2, 1.8, 4.0e9, 1 << 20),
]

# The route scan: dsp/src/seqslam.cpp's DifferenceRows<Rows>, one instance per route storage
# (Float32Rows, BFloat16Rows, CodeRows<unsigned char> for codes8, CodeRows<unsigned short>
# for codes16; each a function of its own in the Release builds, so qemu's log names it).
# A substring of the symbol's name, mangled or not.
SCAN_FUNCTIONS = ["DifferenceRows"]

QEMU = {"aarch64": "qemu-aarch64-static", "armhf": "qemu-arm-static", "x86_64": "qemu-x86_64-static"}


def count(qemu, sysroot, binary, args):
    """Runs binary under qemu with block logging; returns (total, per-function counts, stdout)."""
    cmd = [qemu, "-d", "in_asm,exec,nochain"]
    if sysroot:
        cmd += ["-L", sysroot]
    cmd += [binary] + args
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, bufsize=1 << 20)
    # A block's instruction count goes from its translation (IN:, a listing of guest
    # instructions) to its first run (the first Trace line of its guest address), keyed by
    # that guest address: the program's shared libraries start threads of their own (two,
    # before main), whose translations and runs interleave with the main thread's in the log.
    blocks = {}  # host address of a translated block -> (guest instructions, function)
    pending = {}  # guest address -> instructions of a logged translation, until it first runs
    in_block = None  # the translation being listed: [guest address, instructions]
    per_function = collections.Counter()
    for line in proc.stderr:
        if in_block is not None:
            if line.startswith(b"0x"):
                if in_block[0] is None:
                    in_block[0] = int(line.split(b":", 1)[0], 16)
                in_block[1] += 1
            elif not line.strip():
                pending[in_block[0]] = in_block[1]
                in_block = None
        elif line.startswith(b"Trace "):
            # Trace CPU: HOST [CS_BASE/GUEST/FLAGS/CFLAGS] FUNCTION
            parts = line.split(b" ", 4)
            host = parts[2]
            guest = int(parts[3].split(b"/")[1], 16)
            n = pending.pop(guest, None)
            if n is not None:  # its first run: a new block (maybe at a reused address)
                name = parts[4].strip().decode(errors="replace") if len(parts) > 4 else "?"
                blocks[host] = (n, name or "?")
            n, name = blocks[host]
            per_function[name] += n
        elif line.startswith(b"IN:"):
            in_block = [None, 0]
    out = proc.stdout.read()
    proc.wait()
    if proc.returncode != 0:
        sys.exit(f"{' '.join(cmd)} failed ({proc.returncode}): {out.decode(errors='replace')}")
    return sum(per_function.values()), per_function, out.decode(errors="replace").strip()


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--arch", choices=sorted(QEMU), required=True)
    parser.add_argument("--binary", required=True, help="stage_cost of that architecture")
    parser.add_argument("--sysroot", default="", help="qemu -L: the target's root (cross builds)")
    parser.add_argument("--repetitions", type=int, default=4, help="R: counts at R and 2R")
    parser.add_argument("--functions", type=int, default=0, help="show the N costliest functions")
    parser.add_argument("--model", action="store_true", help="modelled ms on the CORES above")
    parser.add_argument("cases", nargs="*", default=DEFAULT_CASES)
    a = parser.parse_args()
    with tempfile.TemporaryDirectory(prefix="stage-cost-", dir=os.path.dirname(os.path.abspath(a.binary))) as images:
        # The street frames rendered once, without logging (rendering is most of the set-up).
        qemu = [QEMU[a.arch]] + (["-L", a.sysroot] if a.sysroot else [])
        subprocess.run(qemu + [a.binary, "render", "0", "1", "float32", images], check=True)
        run_cases(a, images)


def run_cases(a, images):
    r = a.repetitions
    print(f"# {a.arch}: instructions per repetition = (count at {2 * r} - count at {r}) / {r}")
    for case in a.cases:
        fields = case.split(":")
        stage, route, storage = (fields + ["10000", "float32"][len(fields) - 1:])[:3]
        args = [route, storage, images]
        once = count(QEMU[a.arch], a.sysroot, a.binary, [stage, str(r)] + args)
        twice = count(QEMU[a.arch], a.sysroot, a.binary, [stage, str(2 * r)] + args)
        per = (twice[0] - once[0]) / r
        print(f"{case:24s} {per:14.0f}   ({twice[2].splitlines()[-1]})", flush=True)
        diff = collections.Counter(twice[1])
        diff.subtract(once[1])
        if a.model:
            scan = sum(n for name, n in diff.items() if any(f in name for f in SCAN_FUNCTIONS)) / r
            m = re.search(r"route bytes per step (\d+)", twice[2])
            scan_bytes = int(m.group(1)) if m else 0
            if not scan:
                scan_bytes = 0  # no route scan in this stage
            parts = []
            for name, clock, ipc_low, ipc_high, bandwidth, l2 in CORES:
                memory = scan_bytes / bandwidth if scan_bytes > l2 else 0.0  # else it stays in L2
                ms = [1e3 * ((per - scan) / (ipc * clock) + max(scan / (ipc * clock), memory))
                      for ipc in (ipc_low, ipc_high)]
                parts.append(f"{name} {ms[1]:.3f}-{ms[0]:.3f} ms")
            print(f"    model: {', '.join(parts)} (scan {scan:.0f} instructions, {scan_bytes} bytes)")
        if a.functions:
            for name, n in diff.most_common(a.functions):
                print(f"    {n / r:14.0f}  {name}")


if __name__ == "__main__":
    main()
