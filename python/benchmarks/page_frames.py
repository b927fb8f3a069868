"""The animation page's frame rate, outside CI: writes docs/benchmarks/page.json (docs/tool.md
quotes it).

    python python/benchmarks/page_frames.py        # with the wheel and Debian's chromium

Three models of 40 bodies, each simulated for 2 s and written as a page: a carousel of 40
capsules (40 shaped bodies) on one turning frame; the same carousel with each body an STL mesh
of a sphere of 14,400 triangles (the page carries 20,000 mesh triangles at most, shared among
all its meshes, drawn from both sides); and the pendulum on a cart with 39 links (40 bodies
drawn as inertia cubes, linked by rods); and the capsules again with antialiasing asked for
(`&antialias=1`), which the page leaves out where WebGL is drawn in software, as here.
Each page is opened in headless Chromium at 1280 x 720 with `&measure=300` and played: the
page draws 300 frames one after another through the run, each when the browser asks for one
(requestAnimationFrame: at most the display's rate, 60 a second), and records the frames per
second it delivered (drawing, compositing and showing included) and its own script's time per
frame (the part of a frame that does not depend on how WebGL is drawn). The benchmark waits for
the measure through Chromium's DevTools protocol on a pipe (`--remote-debugging-pipe`; the
standard library only), while the page plays. An empty page is played the same way first (the
display's rate here), and one with the page's three layers cleared at every frame, nothing else
drawn (the least a frame of the page costs here). Three rounds, pages alternated, the round with the most frames per second
kept (as the other benchmarks keep the least disturbed round: this machine's speed varies from
minute to minute), every round's figure recorded. Headless Chromium draws WebGL in software
(`--disable-gpu`: SwiftShader) and, compositing in software too, reads each frame of WebGL back
to the processor; a laptop's browser draws and composites on its GPU.
"""

import json
import math
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import multibody

ROOT = Path(__file__).resolve().parents[2]
OUT = ROOT / "docs" / "benchmarks" / "page.json"
CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")
FRAMES = 300
ROUNDS = 3


def sphere_stl(path, bands=60, sides=120):
    """A text STL of a unit sphere of 2 * bands * sides triangles (14,400 by default)."""
    def at(j, k):
        a, b = math.pi * j / bands, 2 * math.pi * k / sides
        return (math.sin(a) * math.cos(b), math.sin(a) * math.sin(b), math.cos(a))

    facets = []
    for j in range(bands):
        for k in range(sides):
            for tri in [(at(j, k), at(j + 1, k), at(j + 1, k + 1)), (at(j, k), at(j + 1, k + 1), at(j, k + 1))]:
                facets.append("facet normal 0 0 0\nouter loop\n" + "".join("vertex %.6f %.6f %.6f\n" % v for v in tri) + "endloop\nendfacet\n")
    path.write_text("solid sphere\n" + "".join(facets) + "endsolid sphere\n")


def carousel(bodies=40, mesh=None):
    """A RON model: `bodies` capsules (or, given `mesh`, that STL file scaled to a 0.08 radius)
    around a frame turning about the vertical."""
    rows = []
    for k in range(bodies):
        ring, slot = divmod(k, 10)
        angle = 2 * math.pi * slot / 10
        radius = 0.6 + 0.4 * ring
        x, y = radius * math.cos(angle), radius * math.sin(angle)
        rows.append(
            f'Body(name: "b{k}", frame: "disk", mass: "1", com: ["{x:.6f}", "{y:.6f}", "0"], '
            f'inertia: Diagonal(["0.01", "0.01", "0.01"]), '
            + (
                f'shape: Mesh(file: "{mesh}", scale: ["0.08", "0.08", "0.08"], origin: ["{x:.6f}", "{y:.6f}", "0"])),'
                if mesh
                else f'shape: Capsule(radius: "0.06", length: "0.2", origin: ["{x:.6f}", "{y:.6f}", "0"])),'
            )
        )
    return (
        'Model(name: "carousel", parameters: {"g": 9.81}, coordinates: ["theta"],\n'
        '  frames: [Frame(name: "disk", parent: "world", rotation: [Z("theta")])],\n'
        "  bodies: [\n    " + "\n    ".join(rows) + "\n  ],\n"
        '  forces: [Gravity(vector: ["0", "0", "-g"])],\n'
        '  quasi_velocities: QuasiVelocities(full: ["theta\'"], reduced: []),\n'
        '  initial: Initial(q: {"theta": "0"}, qdot: {"theta": "1"}),\n'
        ")\n"
    )


def played(url):
    """Open `url` in headless Chromium and wait (up to two minutes) for the page's measure; the
    page's state (`window.multibody`) and the errors it kept."""
    profile = tempfile.mkdtemp()
    flags = ["--headless", "--no-sandbox", "--disable-gpu", "--enable-unsafe-swiftshader", "--hide-scrollbars", "--window-size=1280,800", f"--user-data-dir={profile}", "--no-first-run", "--disable-background-networking", "--disable-component-update", "--disable-sync"]
    # The protocol's pipe: Chromium reads commands on its fd 3 and answers on its fd 4, each
    # message JSON ended by a NUL.
    commands_read, commands_write = os.pipe()
    answers_read, answers_write = os.pipe()

    def on_fds_3_and_4():
        # Through copies above 4 first: a pipe's end may already be fd 3 or 4.
        reads, writes = os.dup(commands_read), os.dup(answers_write)
        os.dup2(reads, 3)
        os.dup2(writes, 4)

    browser = subprocess.Popen([CHROMIUM, *flags, "--remote-debugging-pipe", url], preexec_fn=on_fds_3_and_4, close_fds=False, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    os.close(commands_read)
    os.close(answers_write)
    answers = os.fdopen(answers_read, "rb")
    pending = b""
    asked = 0

    def ask(method, params=None, session=None):
        nonlocal asked, pending
        asked += 1
        message = {"id": asked, "method": method, "params": params or {}}
        if session:
            message["sessionId"] = session
        os.write(commands_write, json.dumps(message).encode() + b"\0")
        while True:
            while b"\0" not in pending:
                chunk = answers.read1(1 << 16)
                if not chunk:
                    raise RuntimeError(f"Chromium closed its pipe answering {method}")
                pending += chunk
            text, pending = pending.split(b"\0", 1)
            answer = json.loads(text)
            if answer.get("id") == asked:
                if "error" in answer:
                    raise RuntimeError(f"{method}: {answer['error']}")
                return answer["result"]

    try:
        page = next(t for t in ask("Target.getTargets")["targetInfos"] if t["type"] == "page")
        session = ask("Target.attachToTarget", {"targetId": page["targetId"], "flatten": True})["sessionId"]
        # Waits in the page until its measure is in the state (or two minutes have passed).
        wait = """new Promise((done) => {
            const until = performance.now() + 120000;
            const look = () => (window.multibody && window.multibody.frames) || performance.now() > until
                ? done(JSON.stringify({ state: window.multibody || null, errors: (document.getElementById("errors") || {}).textContent || "" }))
                : setTimeout(look, 200);
            look();
        })"""
        # Asked while the page still loads, the wait is lost with the document it ran in.
        for attempt in range(50):
            try:
                result = ask("Runtime.evaluate", {"expression": wait, "awaitPromise": True, "returnByValue": True}, session)
                break
            except RuntimeError as e:
                if "context was destroyed" not in str(e) or attempt == 49:
                    raise
                time.sleep(0.2)
        found = json.loads(result["result"]["value"])
        try:
            ask("Browser.close")
        except RuntimeError:
            pass  # closing, Chromium may close the pipe before it answers
        return found["state"], found["errors"]
    finally:
        os.close(commands_write)
        answers.close()
        try:
            browser.wait(timeout=30)
        except subprocess.TimeoutExpired:
            browser.kill()
        shutil.rmtree(profile, ignore_errors=True)


def measure(page, extra=""):
    state, errors = played(page.as_uri() + f"#t=0&size=1280x720&measure={FRAMES}" + extra)
    assert errors.strip() == "", errors
    frames = state["frames"]
    assert frames["count"] == FRAMES
    return {
        "bodies": len(state["bodies"]),
        "shaped_bodies": state["shaped"],
        "triangles_drawn": state["triangles"],
        "shadow_triangles_drawn": state["shadowTriangles"],
        "antialias": state["antialias"],
        "frames_per_second": round(frames["per_second"], 1),
        "slowest_gap_ms": round(frames["slowest_gap"], 1),
        "script_median_ms": round(frames["script_median"], 2),
        "script_slowest_ms": round(frames["script_slowest"], 2),
    }


# An empty page asking for a frame each time (`&measure=N` as the animation's), and the same
# with the animation's three layers at 1280 x 720 (2-D, WebGL with a depth and a stencil buffer
# kept between frames as the page's, 2-D) cleared and marked at every frame, nothing else drawn.
EMPTY = """<!DOCTYPE html><html><body style="margin: 0"><pre id="errors"></pre>
<div id="stage" style="position: relative; width: 1280px; height: 720px"></div>
<script>
const layers = /layers=1/.test(location.hash), canvases = [];
if (layers) for (let k = 0; k < 3; k++) {
  const c = document.createElement("canvas");
  c.width = 1280; c.height = 720; c.style = "position: absolute; left: 0; top: 0";
  document.getElementById("stage").appendChild(c); canvases.push(c);
}
const under = layers && canvases[0].getContext("2d"), over = layers && canvases[2].getContext("2d");
const gl = layers && canvases[1].getContext("webgl2", { alpha: true, stencil: true, antialias: false, preserveDrawingBuffer: true });
const count = Number(/measure=([0-9]+)/.exec(location.hash)[1]), stamps = [];
const frame = (clock) => {
  stamps.push(clock);
  if (stamps.length > count) { window.multibody = { frames: { per_second: 1000 * count / (clock - stamps[0]) } }; return; }
  if (layers) {
    under.fillStyle = "#ffffff"; under.fillRect(0, 0, 1280, 720); under.fillStyle = "#dddddd"; under.fillRect(stamps.length % 1280, 0, 1, 720);
    gl.clearColor(1, 1, 1, 0); gl.clear(gl.COLOR_BUFFER_BIT | gl.DEPTH_BUFFER_BIT | gl.STENCIL_BUFFER_BIT);
    over.clearRect(0, 0, 1280, 720); over.fillStyle = "#d62728"; over.fillRect(stamps.length % 1280, 10, 4, 4);
  }
  requestAnimationFrame(frame);
};
requestAnimationFrame(frame);
</script></body></html>
"""


def empty_rate(folder, layers):
    """Frames per second of the empty page, with or without the animation's layers."""
    empty = folder / "empty.html"
    empty.write_text(EMPTY)
    state, errors = played(empty.as_uri() + f"#measure={FRAMES}" + ("&layers=1" if layers else ""))
    assert errors.strip() == "", errors
    return round(state["frames"]["per_second"], 1)


def main():
    if not CHROMIUM:
        sys.exit("needs Debian's chromium (apt install chromium)")
    chromium_version = subprocess.run([CHROMIUM, "--version"], capture_output=True, text=True).stdout.strip()
    results = {}
    with tempfile.TemporaryDirectory() as folder:
        folder = Path(folder)
        (folder / "carousel.ron").write_text(carousel())
        sphere_stl(folder / "sphere.stl")
        (folder / "meshes.ron").write_text(carousel(mesh="sphere.stl"))
        cases = {
            "carousel_40_capsules": multibody.load(str(folder / "carousel.ron")),
            "carousel_40_meshes": multibody.load(str(folder / "meshes.ron")),
            "pendulum_on_cart_39": multibody.pendulum_on_cart(39),
        }
        pages = {}
        for name, m in cases.items():
            print(f"{name}: simulating", flush=True)
            run = m.simulate("kane", t_end=2.0, dt_out=0.01, frame=False)
            pages[name] = folder / f"{name}.html"
            m.animate(run, pages[name])
        # The capsules again with antialiasing asked for, which a software renderer otherwise
        # leaves out: what it would cost.
        variants = {name: (page, "") for name, page in pages.items()}
        variants["carousel_40_capsules_antialiased"] = (pages["carousel_40_capsules"], "&antialias=1")
        rounds = {name: [] for name in variants}
        displays, emptied = [], []
        for k in range(ROUNDS):
            displays.append(empty_rate(folder, layers=False))
            emptied.append(empty_rate(folder, layers=True))
            print(f"round {k + 1}: an empty page plays at {displays[-1]} frames per second, its layers cleared at {emptied[-1]}", flush=True)
            for name, (page, extra) in variants.items():
                print(f"{name}: round {k + 1}, playing {FRAMES} frames", flush=True)
                rounds[name].append(measure(page, extra))
        for name, measured in rounds.items():
            results[name] = dict(max(measured, key=lambda r: r["frames_per_second"]))
            results[name]["round_frames_per_second"] = [r["frames_per_second"] for r in measured]
            print(f"  {name}: {results[name]}", flush=True)
    OUT.write_text(
        json.dumps(
            {
                "command": "python python/benchmarks/page_frames.py",
                "browser": chromium_version + " (headless, --disable-gpu: WebGL drawn in software by SwiftShader)",
                "size": "1280x720",
                "frames": FRAMES,
                "rounds": ROUNDS,
                "display_frames_per_second": max(displays),
                "empty_layers_frames_per_second": max(emptied),
                "results": results,
            },
            indent=2,
        )
        + "\n"
    )
    print(f"wrote {OUT}")


if __name__ == "__main__":
    main()
