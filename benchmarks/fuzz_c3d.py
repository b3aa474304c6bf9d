"""Fault campaign on the C3D reader: seeded corruptions of every shared C3D file.

Run:  .venv/bin/python benchmarks/fuzz_c3d.py [--per-file 50] [--seed 17] [--jobs 2] [--show 5]

Every C3D file under ``../shared/data`` gets ``--per-file`` corruptions (byte changes in
header, parameters and data; zeroed ranges and blocks; truncations; extreme header fields
and parameter values -- frame counts, scale, rate, data start, point/analog counts;
corrupt parameter records -- dimension counts, dimensions, types, offsets, names; control
characters in labels) plus its copies written by ezc3d and by the ``c3d`` package
(:mod:`fuzzygait.testing.c3d_fuzz`). Variants are read by ``read_c3d`` in worker processes
(``--jobs`` of them), many per worker; a worker that dies (a crash) or is silent for 30 s
(a hang) is recorded against the variant it was reading and restarted after it, so the
campaign always finishes. Prints the outcome table; exit status 1 if any variant is a
traceback, a crash, over 10 s, read differently without a note, refused in more than one
line, or a written file read back different.
"""

from __future__ import annotations

from _setup import ROOT, one_thread

one_thread()

import argparse  # noqa: E402
import json  # noqa: E402
import os  # noqa: E402
import selectors  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
import threading  # noqa: E402
import time  # noqa: E402
from collections import Counter  # noqa: E402
from pathlib import Path  # noqa: E402

from fuzzygait.testing.c3d_fuzz import OUTCOMES, Variant, save_specs, variants  # noqa: E402

SHARED = ROOT.parent / "shared" / "data"
SILENT_S = 30.0  # a worker silent this long is hung on the current variant
BAD = list(OUTCOMES[6:])


def shared_c3d() -> list[Path]:
    """Every C3D file of the shared data, sorted."""
    return sorted(p for p in SHARED.rglob("*") if p.suffix.lower() == ".c3d")


def run_shard(specs: list[Variant], results: dict[int, dict], offset: int) -> None:
    """Read ``specs`` in worker processes, restarting after a crash or hang."""
    with tempfile.NamedTemporaryFile("w", suffix=".json", delete=False) as handle:
        spec_file = Path(handle.name)
    save_specs(specs, spec_file)
    start = 0
    env = dict(os.environ, PYTHONWARNINGS="ignore")
    try:
        while start < len(specs):
            proc = subprocess.Popen(
                [sys.executable, "-m", "fuzzygait.testing.c3d_fuzz", str(spec_file), str(start)],
                stdout=subprocess.PIPE,
                stderr=subprocess.DEVNULL,
                env=env,
            )
            assert proc.stdout is not None
            selector = selectors.DefaultSelector()
            selector.register(proc.stdout, selectors.EVENT_READ)
            buffer = b""
            began = time.monotonic()
            while True:
                if not selector.select(timeout=SILENT_S):
                    proc.kill()
                    proc.wait()
                    hung = time.monotonic() - began
                    results[offset + start] = {"outcome": "over 10 s", "what": "hung", "seconds": hung}
                    start += 1
                    break
                chunk = os.read(proc.stdout.fileno(), 65536)
                if not chunk:  # the worker died (or finished)
                    code = proc.wait()
                    if start < len(specs):
                        results[offset + start] = {"outcome": "crash", "what": f"worker exit {code}", "seconds": 0.0}
                        start += 1
                    break
                buffer += chunk
                *lines, buffer = buffer.split(b"\n")
                for line in lines:
                    if line.startswith(b"{"):
                        record = json.loads(line)
                        results[offset + record["index"]] = record
                        start = record["index"] + 1
                        began = time.monotonic()
            selector.close()
            proc.stdout.close()
    finally:
        spec_file.unlink(missing_ok=True)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--per-file", type=int, default=50, help="corruptions per shared file")
    parser.add_argument("--seed", type=int, default=17)
    parser.add_argument("--jobs", type=int, default=2, help="worker processes")
    parser.add_argument("--show", type=int, default=5, help="examples to print per outcome")
    args = parser.parse_args()
    sources = shared_c3d()
    if not sources:
        print(f"no C3D files under {SHARED}")
        return 1
    specs = variants(sources, args.per_file, seed=args.seed)
    results: dict[int, dict] = {}
    began = time.perf_counter()
    shards = [(specs[i :: args.jobs], i) for i in range(args.jobs)]
    shard_results: list[dict[int, dict]] = [{} for _ in shards]
    threads = [
        threading.Thread(target=run_shard, args=(shard, shard_results[k], 0)) for k, (shard, _) in enumerate(shards)
    ]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    for k, (_, first) in enumerate(shards):
        for j, record in shard_results[k].items():
            results[first + j * args.jobs] = record
    elapsed = time.perf_counter() - began

    built = {i: r for i, r in results.items() if r.get("outcome")}
    counts = Counter(r["outcome"] for r in built.values())
    seconds = sorted(r.get("seconds", 0.0) for r in built.values())
    unbuilt = len(specs) - len(built)
    print(f"{len(sources)} shared C3D files, {len(specs)} variants ({unbuilt} not built), seed {args.seed}")
    median = seconds[len(seconds) // 2] * 1e3
    print(
        f"campaign {elapsed:.0f} s, {args.jobs} workers; median {median:.0f} ms per variant, max {seconds[-1]:.2f} s\n"
    )
    print("| outcome | variants |\n|---|---:|")
    for outcome in OUTCOMES:
        print(f"| {outcome} | {counts.get(outcome, 0)} |")
    by_kind: dict[str, Counter[str]] = {}
    for i, record in built.items():
        by_kind.setdefault(specs[i].kind, Counter())[record["outcome"]] += 1
    print("\n| kind | " + " | ".join(o.split(" (")[0] for o in OUTCOMES[:6]) + " | other |")
    print("|---|" + "---:|" * 7)
    for kind, kc in sorted(by_kind.items()):
        other = sum(n for o, n in kc.items() if o in BAD)
        print(f"| {kind} | " + " | ".join(str(kc.get(o, 0)) for o in OUTCOMES[:6]) + f" | {other} |")
    for outcome in [*BAD, "refused in one line", "read with a note"]:
        shown = [(i, r) for i, r in sorted(built.items()) if r["outcome"] == outcome][: args.show]
        if shown:
            print(f"\n{outcome}:")
            for i, record in shown:
                print(f"  {specs[i].name}: {record['what']}: {record.get('message', '')[:200]}")
    return 1 if any(counts.get(o) for o in BAD) else 0


if __name__ == "__main__":
    raise SystemExit(main())
