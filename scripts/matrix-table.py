#!/usr/bin/env python3
"""Prints the pipelines × methods tables of BENCHMARKS.md from the JSON reports that
`scripts/bench-device.sh lights decals` writes (unpack its timings.tgz, pass the folder)."""
import json
import pathlib
import sys

RASTER = ("visbuffer_raster", "gbuffer_raster", "depth_prepass")
SHADE = ("visbuffer_shade", "deferred_shade", "forward_shade")


def row(report):
    passes = report["passes"]
    median = lambda names: sum(passes[n]["median_ms"] for n in names if n in passes)
    builds = [n for n in passes if n.endswith("_build")]
    cells = [
        median(builds) if builds else None,
        median(RASTER),
        passes["deferred_decals"]["median_ms"] if "deferred_decals" in passes else None,
        median(SHADE),
        report["frame"]["median_ms"],
        report["frame"]["p95_ms"],
    ]
    return ["—" if c is None else f"{c:.3f}" for c in cells] + [str(report["timed_frames"])]


def main(folder):
    reports = {p.stem: json.loads(p.read_text()) for p in sorted(pathlib.Path(folder).glob("*.json"))}
    for prefix, title in (("lights", "28k small lights"), ("decals", "100k decals (≈ 1 m)"), ("decals03", "100k decals of 0.3 m")):
        print(f"\n{title}\n")
        print("| pipeline | method | build ms | raster ms | deferred decals ms | shade ms | frame ms | p95 | frames |")
        print("| --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
        for pipeline in ("visbuffer", "deferred", "forward"):
            for method in ("off", "brute", "bvh", "bvh-gpu", "clustered", "deferred-decals"):
                report = reports.get(f"{prefix}_{pipeline}_{method}")
                if report:
                    print("| " + " | ".join([pipeline, method] + row(report)) + " |")
    any_report = next(iter(reports.values()))
    print(f"\ndevice: {any_report['device']}; commit {any_report['commit']}; {any_report['width']}×{any_report['height']}")


if __name__ == "__main__":
    main(sys.argv[1])
