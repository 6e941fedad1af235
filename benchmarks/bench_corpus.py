"""The whole public corpus through `robotkit import`, `build` and `check`: pass figures per stage
and errors per rule (tests/corpus/ runs a sample of it under CI).

    python benchmarks/bench_corpus.py [-j N] [--out DIR] [--only NAME ...]

The corpus is tests/corpus/robots.tsv (the PyPI packages rtb-data and example-robot-data:
installed, or unzipped into $ROBOTKIT_CORPUS) and ../shared/assets/robots.  N robots run at once
(default: the cores this process may use), each stage in its own process with one job.  Each
robot's result is appended to OUT/results.jsonl as it finishes (OUT/<robot>/ keeps its recipe,
build and each stage's log); the figures are printed at the end, as Markdown."""

from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile
import time
from concurrent.futures import ThreadPoolExecutor, as_completed
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

from tests.corpus.corpus import robots, run  # noqa: E402


def figures(results: list[dict]) -> list[str]:
    """The Markdown table of pass figures per stage and the errors per rule."""
    n = len(results)
    reached = {"imported": 0, "built": 0, "checked": 0}
    order = ["imported", "built", "checked"]
    for r in results:
        if r["reached"] in order:
            for stage in order[: order.index(r["reached"]) + 1]:
                reached[stage] += 1
    clean = sum(r["clean"] for r in results)
    own = sum(bool(r["own"]) for r in results)
    lines = ["| robots | imported | built | checked | clean (no error) | with an error of robotkit's own |",
             "|---|---|---|---|---|---|",
             f"| {n} | {reached['imported']} | {reached['built']} | {reached['checked']} | {clean} | {own} |", "",
             "| rule (check errors) | robots | errors |", "|---|---|---|"]
    rules: dict[str, list[int]] = {}
    for r in results:
        for rule, count in r["error_counts"].items():
            rules.setdefault(rule, [0, 0])
            rules[rule][0] += 1
            rules[rule][1] += count
    lines += [f"| {rule} | {a} | {b} |" for rule, (a, b) in sorted(rules.items(), key=lambda kv: -kv[1][0])]
    return lines


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("-j", type=int, default=len(os.sched_getaffinity(0)))
    parser.add_argument("--out", type=Path, default=None)
    parser.add_argument("--only", nargs="*", default=None, help="these robots, in this order")
    parser.add_argument("--first", nargs="*", default=[], help="run these robots first, in this order")
    parser.add_argument("--resume", action="store_true", help="skip the robots OUT/results.jsonl already holds")
    a = parser.parse_args()
    out = a.out or Path(tempfile.mkdtemp(prefix="corpus-"))
    out.mkdir(parents=True, exist_ok=True)
    corpus = robots()
    names = [n for n in a.only if n in corpus] if a.only is not None else list(corpus)
    names = [n for n in a.first if n in names] + [n for n in names if n not in a.first]
    if a.resume and (out / "results.jsonl").is_file():
        done = {json.loads(line)["robot"] for line in open(out / "results.jsonl", encoding="utf-8")}
        names = [n for n in names if n not in done]
    print(f"{len(names)} robots into {out}, {a.j} at once", flush=True)
    t = time.perf_counter()
    results = []
    with ThreadPoolExecutor(a.j) as pool, open(out / "results.jsonl", "a", encoding="utf-8") as log:
        futures = {pool.submit(run, corpus[n], out / n): n for n in names}
        for done in as_completed(futures):
            summary = done.result().summary()
            results.append(summary)
            log.write(json.dumps(summary) + "\n")
            log.flush()
            print(f"{summary['robot']}: {summary['reached']}, clean={summary['clean']}, errors={summary['errors']}, "
                  f"own={len(summary['own'])}", flush=True)
    print(f"\n{len(names)} robots in {time.perf_counter() - t:.0f} s ({a.j} at once)\n")
    print("\n".join(figures(results)))


if __name__ == "__main__":
    main()
