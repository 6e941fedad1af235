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
import re
import sys
import tempfile
import time
from concurrent.futures import ThreadPoolExecutor, as_completed
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

from tests.corpus.corpus import own_finding, reported, robots, run  # noqa: E402


def figures(results: list[dict]) -> list[str]:
    """The Markdown tables: robots per stage reached, and the check's errors per rule (whose: robotkit's
    own, or the original's defect)."""
    order = ["imported", "built", "checked"]
    reached = {stage: sum(r["reached"] in order[order.index(stage):] for r in results) for stage in order}
    clean = sum(r["clean"] for r in results)
    own = sum(bool(r["own"]) for r in results)
    share = f"{100 * clean / reached['built']:.0f} %" if reached["built"] else "-"
    lines = ["| robots | imported | built | checked | clean (no error) | clean / built | with an error of robotkit's own |",
             "|---|---|---|---|---|---|---|",
             f"| {len(results)} | {reached['imported']} | {reached['built']} | {reached['checked']} | {clean} | {share} "
             f"| {own} |", "", "| rule (check errors) | whose | robots | errors |", "|---|---|---|---|"]
    rules: dict[str, list[int]] = {}
    owners: dict[str, str] = {}
    for r in results:
        for rule, count in r["error_counts"].items():
            rules.setdefault(rule, [0, 0])
            rules[rule][0] += 1
            rules[rule][1] += count
            if any(o.startswith(f"check: {rule}:") for o in r["own"]):
                owners[rule] = "robotkit"
    lines += [f"| {rule} | {owners.get(rule, 'original')} | {a} | {b} |"
              for rule, (a, b) in sorted(rules.items(), key=lambda kv: (-kv[1][0], kv[0]))]
    unreported = {r["robot"]: r["unreported"] for r in results if r.get("unreported")}
    if unreported:
        lines += ["", "Errors of the original's that the import did not report: "
                  + "; ".join(f"{robot}: {', '.join(found)}" for robot, found in sorted(unreported.items()))]
    refusals: dict[tuple[str, str], list[str]] = {}
    for r in results:
        if r["reached"].startswith("refused"):
            refusals.setdefault((r["reached"], cause(r["refusal"])), []).append(r["robot"])
    lines += ["", "| refused | cause | robots |", "|---|---|---|"]
    lines += [f"| {stage.removeprefix('refused by ')} | {why} | {len(names)}: {', '.join(sorted(names))} |"
              for (stage, why), names in sorted(refusals.items(), key=lambda kv: -len(kv[1]))]
    return lines


CAUSES = [("not a valid recipe name", "link names with a leading slash"),
          ("cannot mimic", "<mimic> on a fixed joint"),
          (re.compile(r"limit\.(lower|upper): Input should be"), "limits beyond +-10000 (meaning unlimited)"),
          (re.compile(r":\d+: xacro: "), "xacro expansion"),
          ("give --package-path", "a package the table does not give"),
          ("Traceback", "traceback"), ("timed out after", "timed out (900 s per stage)")]


def cause(lines: list[str]) -> str:
    """The refusal's cause, in a few words (the first line's message when none of CAUSES)."""
    text = "\n".join(lines)
    for pattern, why in CAUSES:
        if (pattern.search(text) if isinstance(pattern, re.Pattern) else pattern in text):
            return why
    return re.sub(r"^\S+: ", "", lines[0] if lines else "(no message)")[:100]


def reclassify(summary: dict, out: Path) -> dict:
    """``summary`` with its check errors classified by today's own_finding (from OUT/<robot>/check.json),
    and ``unreported``: the original's errors no line of the import's output names (import.log)."""
    report = out / summary["robot"] / "check.json"
    if report.is_file():
        errors = [f for f in json.loads(report.read_text(encoding="utf-8"))["findings"] if f["severity"] == "error"]
        stage = ("check: traceback", "check: timed out", "check: exit")  # the check process's own, kept
        summary["own"] = [o for o in summary["own"] if not o.startswith("check: ") or o.startswith(stage)]
        summary["own"] += [f"check: {f['check']}: {f['subject']}: {f['message']}" for f in errors if own_finding(f)]
        log = out / summary["robot"] / "import.log"
        said = log.read_text(encoding="utf-8") if log.is_file() else ""
        summary["unreported"] = [f"{f['check']} {f['subject']}" for f in errors
                                 if not own_finding(f) and not reported(f, said)]
    return summary


def read_results(outs: list[Path]) -> list[dict]:
    """Each robot's last result in OUT/results.jsonl of ``outs``, a later folder's over an earlier's."""
    last = {}
    for out in outs:
        for line in open(out / "results.jsonl", encoding="utf-8"):
            summary = reclassify(json.loads(line), out)
            if summary["reached"].startswith("refused") and not summary["refusal"]:  # before refusal() said why
                summary["refusal"] = [o for o in summary["own"] if "timed out" in o]
            last[summary["robot"]] = summary
    return list(last.values())


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("-j", type=int, default=len(os.sched_getaffinity(0)))
    parser.add_argument("--out", type=Path, default=None)
    parser.add_argument("--only", nargs="*", default=None, help="these robots, in this order")
    parser.add_argument("--first", nargs="*", default=[], help="run these robots first, in this order")
    parser.add_argument("--resume", action="store_true", help="skip the robots OUT/results.jsonl already holds")
    parser.add_argument("--figures", action="store_true",
                        help="only print the figures of OUT/results.jsonl (each robot's last result)")
    parser.add_argument("--earlier", nargs="*", type=Path, default=[],
                        help="with --figures: earlier runs' folders, for the robots OUT has not rerun")
    a = parser.parse_args()
    out = a.out or Path(tempfile.mkdtemp(prefix="corpus-"))
    out.mkdir(parents=True, exist_ok=True)
    if a.figures:
        results = read_results([*a.earlier, out])
        print(f"{len(results)} robots\n")
        print("\n".join(figures(results)))
        return
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
