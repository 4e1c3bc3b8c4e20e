#!/usr/bin/env python3
"""`lucent report` in a real headless browser (Debian's chromium): the page loads with no outside
resource, every embedded image decodes to the image's size, flipping a viewer shows the other image,
the numbers shown equal `lucent compare --test`'s, and the chart has a point for each timed candidate.
Controls: a page with a damaged image, and a page with a number changed, are caught by the same checks.
Bad input (labels not matching the candidates, NaN options, images of different sizes) writes no page.

  report_test.py LUCENT_BINARY SOURCE_DIR CHROMIUM
"""
import html.parser
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile

lucent, root, chromium = sys.argv[1], sys.argv[2], sys.argv[3]
scene = os.path.join(root, "scenes", "cornell-box.json")
failures = []


def check(condition, message):
    if not condition:
        failures.append(message)


def run(args, **kw):
    return subprocess.run(args, capture_output=True, text=True, timeout=300, **kw)


def render(path, args, resolution="32x32"):
    run([lucent, "render", scene, "--resolution", resolution, "--quiet", "-o", path] + args).check_returncode()


class Page(html.parser.HTMLParser):
    """The browser's DOM after the page's script ran: <body>'s data attributes, every element's
    data-key text by candidate row or section, and the chart's point labels."""

    def __init__(self, text):
        super().__init__()
        self.body, self.values, self.points = {}, {}, []
        self.scope, self.key, self.text = None, None, ""
        self.feed(text)

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        if tag == "body":
            self.body = {k: v for k, v in a.items() if k.startswith("data-")}
        if tag == "tr" and "data-candidate" in a:
            self.scope = "row-" + a["data-candidate"]
        if tag == "section" and a.get("id", "").startswith("candidate-"):
            self.scope = "section-" + a["id"].split("-")[1]
        if tag == "g" and a.get("class") == "point":
            self.points.append(a["data-label"])
        if "data-key" in a and tag in ("td", "span") and not a["data-key"].endswith(tuple("0123456789")):
            self.key, self.text = a["data-key"], ""

    def handle_data(self, data):
        if self.key:
            self.text += data

    def handle_endtag(self, tag):
        if self.key and tag in ("td", "span"):
            self.values[(self.scope, self.key)] = self.text.strip()
            self.key = None


def browse(page):
    profile = tempfile.mkdtemp()
    try:
        # No network: a resource from outside the page could not load.
        r = run([chromium, "--headless", "--no-sandbox", "--disable-gpu", "--user-data-dir=" + profile,
                 "--host-resolver-rules=MAP * ~NOTFOUND", "--virtual-time-budget=20000", "--dump-dom",
                 "file://" + os.path.abspath(page)])
    finally:
        shutil.rmtree(profile, ignore_errors=True)
    if r.returncode != 0 or "<body" not in r.stdout:
        sys.exit("chromium could not load %s (status %d): %s" % (page, r.returncode, r.stderr[-2000:]))
    return Page(r.stdout)


def fmt(value):
    return "%.4g" % value


def expected_numbers(i, result):
    """What row i and section i of the page must show, from `lucent compare --test`'s JSON."""
    t = result["test"]
    row = "row-%d" % i
    out = {(row, k): fmt(result["overall"][k]) for k in ("relmse", "rmse", "mae", "smape")}
    out[(row, "non_finite")] = str(result["non_finite"])
    f = result["flip"]
    out[(row, "flip")] = fmt(f["mean"])
    section = "section-%d" % i
    out[(section, "flip-mean")] = fmt(f["mean"])
    out[(section, "flip-weighted_median")] = fmt(f["weighted_median"])
    out[(section, "flip-first_quartile")] = fmt(f["weighted_quartiles"][0])
    out[(section, "flip-third_quartile")] = fmt(f["weighted_quartiles"][1])
    words = {"pass": "passed", "fail": "failed", "inconclusive": "inconclusive"}
    out[(row, "passed")] = words[t["verdict"]]
    out[(row, "blocks_rejected")] = str(t["blocks_rejected"])
    out[(row, "fraction_rejected_at_alpha")] = fmt(t["fraction_rejected_at_alpha"])
    out[(row, "relative_difference")] = fmt(t["regions"][0]["relative_difference"])
    out[(row, "z")] = fmt(t["regions"][0]["z"])
    for k, region in enumerate(t["regions"][1:], start=1):
        out[("section-%d" % i, "region-%d-relative_difference" % k)] = fmt(region["relative_difference"])
        out[("section-%d" % i, "region-%d-z" % k)] = fmt(region["z"])
    e = result["equivalence"]
    out[(row, "equivalent")] = words[e["verdict"]]
    out[(row, "interval_low")] = fmt(e["regions"][0]["interval"][0])
    out[(row, "interval_high")] = fmt(e["regions"][0]["interval"][1])
    for k, region in enumerate(e["regions"][1:], start=1):
        out[("section-%d" % i, "region-%d-interval_low" % k)] = fmt(region["interval"][0])
        out[("section-%d" % i, "region-%d-interval_high" % k)] = fmt(region["interval"][1])
    return out


def number_mismatches(page, results):
    wrong = []
    for i, result in enumerate(results):
        for key, want in expected_numbers(i, result).items():
            if page.values.get(key) != want:
                wrong.append("%s: page shows %r, compare says %r" % (key, page.values.get(key), want))
    return wrong


def image_problems(page, candidates):
    b = page.body
    # The reference, and per candidate: the viewer's two, side by side two, three heatmaps, three colour bars.
    expected = 1 + 10 * candidates
    problems = []
    if b.get("data-checked") != "yes":
        problems.append("the page's self-check did not run: %r" % b)
    if b.get("data-images-expected") != str(expected) or b.get("data-images-decoded") != str(expected):
        problems.append("images decoded %s of %s, expected %d" % (b.get("data-images-decoded"),
                                                                  b.get("data-images-expected"), expected))
    if b.get("data-images-failed"):
        problems.append("images that failed: " + b["data-images-failed"])
    if b.get("data-viewers-flipped") != str(candidates):
        problems.append("viewers that flip: %s of %d" % (b.get("data-viewers-flipped"), candidates))
    return problems


def text_of(path):
    with open(path, encoding="utf-8") as f:
        return f.read()


work = tempfile.mkdtemp()
try:
    p = lambda name: os.path.join(work, name)
    render(p("reference.exr"), ["--method", "pt", "--variance", "--sampler", "independent", "--spp", "1024", "--seed", "1",
                                "--layers"])
    render(p("pt.exr"), ["--method", "pt", "--variance", "--sampler", "independent", "--spp", "64", "--seed", "2",
                         "--png", p("pt.png")])
    render(p("micro.exr"), ["--method", "micro"])
    # A sidecar such as a GPU renderer writes beside its image: what rendered it, and its time.
    with open(p("pt.exr.json"), "w") as f:
        json.dump({"renderer": "a GPU tracer", "samples": 64, "seconds": 1.5, "device": "test GPU", "build": "x"}, f)
    candidates = [p("pt.exr"), p("micro.exr"), p("pt.png")]
    labels = ["path tracer <64 spp>", "micro", "8-bit PNG"]
    r = run([lucent, "report", p("reference.exr")] + candidates + sum([["--label", l] for l in labels], []) +
            ["--within", "0.05", "--ldr", "-o", p("report.html")])  # the PNG against the clipped reference
    check(r.returncode == 0, "report failed: " + r.stderr)
    summary = json.loads(r.stdout)
    side = summary["candidates"][0].get("sidecar", {})
    check(side.get("renderer") == "a GPU tracer" and side.get("samples") == 64 and side.get("device") == "test GPU"
          and side.get("not_read") == ["build"], "the sidecar was not read: %r" % side)
    check(summary["candidates"][0].get("seconds") == 1.5, "the sidecar's seconds were not used")
    results = []
    for c in candidates:
        r = run([lucent, "compare", "--test", "--within", "0.05", "--metric", "flip", "--ldr", c, p("reference.exr")])
        check(r.returncode in (0, 1, 3), "compare failed: " + r.stderr)
        results.append(json.loads(r.stdout))
    check([c["test"] for c in summary["candidates"]] == [x["test"]["verdict"] for x in results],
          "the report's JSON verdicts differ from compare's")
    check([c["within"] for c in summary["candidates"]] == [x["equivalence"]["verdict"] for x in results],
          "the report's JSON equivalence verdicts differ from compare's")
    # The reference's layers say what each pixel shows: the report breaks each difference down as compare does.
    for c, x in zip(summary["candidates"], results):
        mine = [(e["name"], fmt(e["relative_difference"])) for e in c.get("by_surface", [])]
        theirs = [(e["name"], fmt(e["relative_difference"])) for e in x["by_surface"]["surfaces"]]
        check(mine == theirs and any(name == "light" for name, _ in mine),
              "the report's breakdown by surface differs from compare's: %r vs %r" % (mine, theirs))
    check(text_of(p("report.html")).count('data-key="by_surface"') == len(candidates),
          "the page does not show each candidate's breakdown by surface")
    # micro and the PNG have no variance layers: neither passed nor failed.
    check([x["test"]["verdict"] for x in results][1:] == ["inconclusive", "inconclusive"],
          "candidates without variance layers are not inconclusive")

    text = text_of(p("report.html"))
    outside = [m for m in re.findall(r'(?:src|href)="([^"]*)"', text) if m and not m.startswith(("data:", "#"))]
    check(not outside, "the page loads outside resources: %r" % outside[:3])
    check("<64 spp>" not in text, "a label reached the page unescaped")

    # Runs: --runs 2 makes each two images one candidate, judged by their spread as compare judges them.
    for seed in ("3", "4"):
        render(p("run%s.exr" % seed), ["--method", "pt", "--spp", "64", "--seed", seed])
    r = run([lucent, "report", p("reference.exr"), p("run3.exr"), p("run4.exr"), "--runs", "2", "--within", "0.05",
             "-o", p("runs.html")])
    check(r.returncode == 0, "report --runs failed: " + r.stderr)
    entry = json.loads(r.stdout)["candidates"]
    r = run([lucent, "compare", p("run3.exr"), p("run4.exr"), p("reference.exr"), "--test", "--within", "0.05", "--json"])
    check(r.returncode in (0, 1, 3), "compare of runs failed: " + r.stderr)
    runs = json.loads(r.stdout)
    check(len(entry) == 1 and entry[0].get("runs") == [p("run3.exr"), p("run4.exr")]
          and entry[0]["test"] == runs["test"]["verdict"] and entry[0]["within"] == runs["equivalence"]["verdict"]
          and fmt(entry[0]["relmse"]) == fmt(runs["overall"]["relmse"]),
          "report --runs differs from compare of the runs: %r" % entry)
    check(run([lucent, "report", p("reference.exr"), p("run3.exr"), p("run4.exr"), p("pt.exr"), "--runs", "2",
               "-o", p("odd.html")]).returncode == 1, "three images in runs of 2 were accepted")

    page = browse(p("report.html"))
    for problem in image_problems(page, len(candidates)):
        check(False, problem)
    for wrong in number_mismatches(page, results):
        check(False, wrong)
    check(page.points == labels[:2], "chart points %r, expected the two timed candidates %r" % (page.points, labels[:2]))

    # Controls: a damaged image is reported by the page, a changed number by the comparison.
    damaged = re.sub(r'(src="data:image/png;base64,)([A-Za-z0-9+/]{200})', r"\1" + "A" * 200, text, count=1)
    with open(p("damaged.html"), "w", encoding="utf-8") as f:
        f.write(damaged)
    check(image_problems(browse(p("damaged.html")), len(candidates)),
          "control: a page with a damaged image passed the image check")
    tampered = re.sub(r'(data-key="relmse">)([^<]*)', lambda m: m.group(1) + fmt(float(m.group(2)) * 1.001), text, count=1)
    check(number_mismatches(Page(tampered), results), "control: a page with a changed number passed the number check")

    # A reference without variance layers: the page says the noise test was not run, and shows no verdict.
    r = run([lucent, "report", p("micro.exr"), p("pt.exr"), "-o", p("untested.html")])
    check(r.returncode == 0 and json.loads(r.stdout)["tested"] is False, "report against micro.exr: " + r.stderr)
    with open(p("untested.html"), encoding="utf-8") as f:
        untested = f.read()
    check('id="untested"' in untested and 'data-key="passed"' not in untested,
          "a reference without variance layers still shows a verdict")

    # Bad input: no page.
    for args, words in ((candidates + ["--label", "one", "-o", p("bad.html")], "--label is given 1 times"),
                        ([p("pt.exr"), "-o", p("reference.exr")], "must end in .html"),
                        ([p("pt.exr"), "--seconds", "nan", "-o", p("bad.html")], "--seconds must be positive"),
                        ([p("pt.exr"), "--alpha", "nan", "-o", p("bad.html")], "--alpha must lie")):
        r = run([lucent, "report", p("reference.exr")] + args)
        check(r.returncode == 1 and words in r.stderr, "bad input %r: status %d, %r" % (args, r.returncode, r.stderr))
    render(p("small.exr"), ["--method", "pt", "--spp", "1"], resolution="16x16")
    r = run([lucent, "report", p("reference.exr"), p("small.exr"), "-o", p("bad.html")])
    check(r.returncode == 1 and "small.exr" in r.stderr, "images of different sizes: %r" % r.stderr)
    check(not os.path.exists(p("bad.html")), "a refused report left a page")
finally:
    shutil.rmtree(work, ignore_errors=True)

for f in failures:
    print("FAILED:", f)
print("%d failures" % len(failures))
sys.exit(1 if failures else 0)
