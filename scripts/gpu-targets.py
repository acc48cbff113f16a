#!/usr/bin/env python3
"""gpu-targets: the tables and the speed targets of a `scripts/gpu-check run`, from its
bench.jsonl (one line per `contrastxr bench --json` it ran) and startup.txt, as Markdown.

    scripts/gpu-targets.py OUT/bench.jsonl [OUT/startup.txt]

The targets (medians of the runs, 2 views):
  srgb     the frame of an sRGB swapchain the runtime refuses storage usage, on each of the
           layer's paths for it (region copied in and back, tiles drawn back, sampled read),
           over the frame in place: <= 1.3 at every size and content
  frame    the whole frame, full content: <= 0.15 ms at 1920x1080, <= 0.3 ms at 2064x2208
  opengl   the OpenGL engine's frame over Vulkan's, same size and content: <= 1.3
  enhance  the enhancement alone over the plain copy, full content, 2064x2208: <= 1.5
  method   the perceptual method's enhancement over the paper's, 2064x2208: <= 2
Only stdlib; runs on the GPU machine (gpu-check run calls it) and here.
"""
import json
import sys

SRGB_PATHS = [
    ("region", "frame_image_copy_ms", "image_copy_in_place_ratio"),
    ("tiles", "frame_image_copy_tiles_ms", "image_copy_tiles_in_place_ratio"),
    ("sampled", "frame_sampled_tiles_ms", "sampled_tiles_in_place_ratio"),
]
FRAME_LIMITS = {(1920, 1080): 0.15, (2064, 2208): 0.3}
COLUMNS = [
    ("copy", "copy_ms"),
    ("enh", "enhance_ms"),
    ("enh/copy", "ratio"),
    ("frame (buffers)", "frame_ms"),
    ("in place", "frame_in_place_ms"),
    ("region", "frame_image_copy_ms"),
    ("region/ip", "image_copy_in_place_ratio"),
    ("tiles", "frame_image_copy_tiles_ms"),
    ("tiles/ip", "image_copy_tiles_in_place_ratio"),
    ("sampled", "frame_sampled_tiles_ms"),
    ("sampled/ip", "sampled_tiles_in_place_ratio"),
]


def fmt(x):
    if x is None:
        return "-"
    return f"{x:.3f}" if x < 10 else f"{x:.1f}"


def verdict(ok):
    return "-" if ok is None else ("met" if ok else "NOT met")


def load(path):
    parts = {}
    with open(path) as f:
        for line in f:
            if line.strip():
                entry = json.loads(line)
                # A part taken again (PARTS=...) replaces its earlier run.
                parts[entry["part"]] = [entry]
    return parts


def results(parts, name, ablation="none"):
    """The rows of a part's runs (the ones without ablation unless asked)."""
    rows = []
    for entry in parts.get(name, []):
        for r in (entry.get("output") or {}).get("results", []):
            if r.get("ablation", "none") == ablation:
                rows.append(r)
    return rows


def key(r):
    return (r["width"], r["height"], r["content"])


def table(rows, out):
    shown = [c for c in COLUMNS if any(r.get(c[1]) is not None for r in rows)]
    out.append("| per view | content | " + " | ".join(c[0] for c in shown) + " |")
    out.append("|---|---|" + "---|" * len(shown))
    for r in rows:
        cells = [fmt(r.get(field)) for _, field in shown]
        out.append(f"| {r['width']}x{r['height']} | {r['content']} | " + " | ".join(cells) + " |")


def srgb_target(vk, out):
    out.append("**srgb** (each path's frame over the frame in place, worst case; target <= 1.3):")
    best = None
    for name, _, ratio in SRGB_PATHS:
        values = [r[ratio] for r in vk if r.get(ratio) is not None]
        if len(values) < len(vk) or not values:
            out.append(f"- {name}: not timed at every size and content")
            continue
        worst = max(values)
        out.append(f"- {name}: worst {worst:.2f}, median row {sorted(values)[len(values) // 2]:.2f}: "
                   f"{verdict(worst <= 1.3)}")
        if best is None or worst < best[1]:
            best = (name, worst)
    if best:
        out.append(f"- lowest worst case: {best[0]} ({best[1]:.2f})")


def frame_target(vk, out):
    out.append("**frame** (full content; 1920x1080 <= 0.15 ms, 2064x2208 <= 0.3 ms):")
    for r in vk:
        limit = FRAME_LIMITS.get((r["width"], r["height"]))
        if limit is None or r["content"] != "full":
            continue
        cells = []
        for name, field in [("in place", "frame_in_place_ms")] + [(n, f) for n, f, _ in SRGB_PATHS]:
            v = r.get(field)
            if v is not None:
                cells.append(f"{name} {v:.3f} ({verdict(v <= limit)})")
        out.append(f"- {r['width']}x{r['height']}: " + ", ".join(cells))


def opengl_target(vk, gl, out):
    out.append("**opengl** (the OpenGL frame over Vulkan's; target <= 1.3):")
    by_key = {key(r): r for r in vk}
    worst = None
    for r in gl:
        v = by_key.get(key(r))
        if not v or not v.get("frame_in_place_ms") or r.get("frame_in_place_ms") is None:
            continue
        ip = r["frame_in_place_ms"] / v["frame_in_place_ms"]
        buffers = r["frame_ms"] / v["frame_ms"] if v.get("frame_ms") else None
        out.append(f"- {r['width']}x{r['height']} {r['content']}: in place {ip:.2f}, "
                   f"through buffers {fmt(buffers)}")
        worst = ip if worst is None else max(worst, ip)
    if worst is not None:
        out.append(f"- worst in place: {worst:.2f}: {verdict(worst <= 1.3)}")


def enhance_target(vk, out):
    out.append("**enhance** (enhancement over the plain copy, full content; 2064x2208 <= 1.5):")
    for r in vk:
        if r["content"] == "full":
            at = (r["width"], r["height"]) == (2064, 2208)
            mark = f": {verdict(r['ratio'] <= 1.5)}" if at else ""
            out.append(f"- {r['width']}x{r['height']}: {r['ratio']:.2f}{mark}")


def method_target(vk, perceptual, out):
    out.append("**method** (perceptual enhancement over the paper's, 2064x2208; <= 2):")
    paper = {key(r): r for r in vk}
    for r in perceptual:
        p = paper.get(key(r))
        if p and p.get("enhance_ms"):
            x = r["enhance_ms"] / p["enhance_ms"]
            out.append(f"- {r['width']}x{r['height']} {r['content']}: {r['enhance_ms']:.3f} / "
                       f"{p['enhance_ms']:.3f} ms = {x:.2f}: {verdict(x <= 2.0)}")


def ablations(parts, out):
    for name in ("ablate-vk", "ablate-gl", "ablate-perceptual", "ablate-perceptual-gl"):
        rows = [r for e in parts.get(name, []) for r in (e.get("output") or {}).get("results", [])]
        if not rows:
            continue
        out.append(f"\n### {name} (enhancement ms, and over none)\n")
        cases = sorted({key(r) for r in rows})
        out.append("| ablation | " + " | ".join(f"{w}x{h} {c}" for w, h, c in cases) + " |")
        out.append("|---|" + "---|" * len(cases))
        for ablation in dict.fromkeys(r["ablation"] for r in rows):
            cells = []
            for case in cases:
                r = next((r for r in rows if key(r) == case and r["ablation"] == ablation), None)
                if r is None:
                    cells.append("-")
                else:
                    vs = r.get("enhance_vs_none")
                    cells.append(fmt(r["enhance_ms"]) + (f" ({vs:.2f})" if vs else ""))
            out.append(f"| {ablation} | " + " | ".join(cells) + " |")


def shader_statistics(parts, out):
    entries = [(name, e) for name in ("vk", "perceptual") for e in parts.get(name, [])]
    for name, entry in entries:
        output = entry.get("output") or {}
        if "shader_statistics_error" in output:
            out.append(f"\n### Shader statistics, {name}\n\nnone: {output['shader_statistics_error']}")
        shaders = output.get("shader_statistics")
        if not shaders:
            continue
        names = list(dict.fromkeys(k for s in shaders for e in s["executables"]
                                   for k in e["statistics"]))
        out.append(f"\n### Shader statistics, {name} (the driver's compiler)\n")
        out.append("| shader | subgroup | " + " | ".join(names) + " |")
        out.append("|---|---|" + "---|" * len(names))
        for s in shaders:
            for e in s["executables"]:
                cells = [str(e["statistics"].get(k, "-")) for k in names]
                out.append(f"| {s['shader']} | {e['subgroup_size']} | " + " | ".join(cells) + " |")


def main(argv):
    if len(argv) < 2:
        print(__doc__.strip())
        return 2
    parts = load(argv[1])
    out = []
    for name, entries in parts.items():
        for e in entries:
            output = e.get("output") or {}
            device = output.get("device", "no output")
            roots = f", cube roots: {output['cube_roots']}" if "cube_roots" in output else ""
            out.append(f"- {name}: `{' '.join(e['args'])}`: exit {e['exit']}, {e['seconds']:.0f} s, "
                       f"{device}{roots}")
    vk, gl = results(parts, "vk"), results(parts, "gl")
    perceptual = results(parts, "perceptual")
    for title, rows in [("Vulkan, paper", vk), ("OpenGL, paper", gl),
                        ("OpenGL, paper, sizes largest first", results(parts, "gl-reversed")),
                        ("Vulkan, perceptual", perceptual)]:
        if rows:
            out.append(f"\n### {title} (ms, medians)\n")
            table(rows, out)
    out.append("\n### Targets\n")
    srgb_target(vk, out)
    frame_target(vk, out)
    opengl_target(vk, gl, out)
    enhance_target(vk, out)
    method_target(vk, perceptual, out)
    ablations(parts, out)
    shader_statistics(parts, out)
    if len(argv) > 2:
        with open(argv[2]) as f:
            out.append("\n### Start-up\n")
            out.extend(f"- {line.rstrip()}" for line in f if line.strip())
    print("\n".join(out))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
