"""The animation page in headless Chromium: it loads without errors, the bodies it draws at two
times are where the trajectory puts them (the page's own state against positions computed here
from the coordinates), and the screenshots show each body's colour at the place the page says."""

import colorsys
import json
import math
import re
import shutil
import subprocess

import numpy as np
import pytest

import multibody

CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")
FLAGS = [
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    # WebGL in software (SwiftShader): Chromium asks for it to be named.
    "--enable-unsafe-swiftshader",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--hide-scrollbars",
    "--window-size=900,650",
]


def chromium(tmp_path, *args):
    assert CHROMIUM, "the browser test needs Debian's chromium (.ci/python installs it)"
    profile = tmp_path / "profile"
    out = subprocess.run([CHROMIUM, *FLAGS, f"--user-data-dir={profile}", *args], capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr[-2000:]
    return out.stdout


def page_dom(tmp_path, url, *flags):
    """The page as the browser left it and the state it drew, asserting that no script error
    and nothing from the console (three.js's errors and warnings) showed."""
    dom = chromium(tmp_path, *flags, "--dump-dom", url)
    errors = re.search(r'<pre id="errors">(.*?)</pre>', dom, re.S).group(1)
    assert errors.strip() == "", errors
    return dom, json.loads(re.search(r'<pre id="state">(.*?)</pre>', dom, re.S).group(1).replace("&quot;", '"'))


def page_state(tmp_path, url):
    return page_dom(tmp_path, url)[1]


def animated(m, path, *args, **kwargs):
    """`m`'s run (``m.simulate(*args, **kwargs)``, as arrays) written as a page at `path`."""
    run = m.simulate(*args, frame=False, **kwargs)
    m.animate(run, path)
    return path, run


def hue_at(image, x, y, radius=4):
    """The hues (degrees) of the saturated pixels in a square around (x, y)."""
    hues = []
    for j in range(int(y) - radius, int(y) + radius + 1):
        for i in range(int(x) - radius, int(x) + radius + 1):
            r, g, b = image.getpixel((i, j))[:3]
            h, s, v = colorsys.rgb_to_hsv(r / 255, g / 255, b / 255)
            if s > 0.35 and v > 0.15:
                hues.append(360 * h)
    return hues


def test_the_page_shows_the_bodies_where_the_trajectory_puts_them(tmp_path):
    from PIL import Image

    m = multibody.load("cart_pendulum")
    path, run = animated(m, tmp_path / "cart pendulum.html", "kane", t_end=3.0, dt_out=0.01)
    html = path.read_text()
    # Self-contained: no address the page would fetch (the XHTML namespace's name, with which
    # three.js makes its canvas, is a name, never fetched).
    addresses = html.replace("http://www.w3.org/1999/xhtml", "")
    assert "http://" not in addresses and "https://" not in addresses and "src=" not in html
    l = m.params["l"]
    names = ["cart", "bar1", "bar2"]
    for t in [0.5, 2.5]:
        i = int(np.argmin(np.abs(run["t"] - t)))
        # Each body as its inertia box, the cart a point (its shape, a box that the bars pierce
        # at its centre, is tested below).
        url = path.as_uri() + f"#t={run['t'][i]}&size=800x520&inertia=1"
        state = page_state(tmp_path, url)
        assert state["webgl"] is True, "the solids are drawn in WebGL"
        assert state["index"] == i and math.isclose(state["t"], run["t"][i])
        x, a, b = run["x"][i], run["theta1"][i], run["theta2"][i]
        expected = {
            "cart": [x, 0.0, 0.0],
            "bar1": [x + l / 2 * math.sin(a), -l / 2 * math.cos(a), 0.0],
            "bar2": [x + l * math.sin(a) + l / 2 * math.sin(b), -l * math.cos(a) - l / 2 * math.cos(b), 0.0],
        }
        assert [body["name"] for body in state["bodies"]] == names
        for body in state["bodies"]:
            assert np.allclose(body["center"], expected[body["name"]], atol=1e-5), (t, body)
        shot = tmp_path / f"shot_{t}.png"
        chromium(tmp_path, f"--screenshot={shot}", url)
        image = Image.open(shot).convert("RGB")
        for k, name in enumerate(names):
            want = (30 + k * 137.508) % 360
            px, py = state["screen"][k]
            hues = hue_at(image, px + state["offset"][0], py + state["offset"][1])
            close = [h for h in hues if min(abs(h - want), 360 - abs(h - want)) < 15]
            assert len(close) >= 10, (t, name, want, hues[:20])
    # The cart moved between the two times, and so did its place on the page.
    assert abs(run["x"][250] - run["x"][50]) > 0.05


def test_the_page_refuses_a_trajectory_of_another_model(tmp_path):
    m = multibody.load("cart_pendulum")
    other = multibody.load("three_body").simulate("kane", t_end=0.2, dt_out=0.1, frame=False)
    with pytest.raises(ValueError, match="the run is of model `three_body`, not of `cart_pendulum`"):
        m.animate(other, tmp_path / "x.html")


def test_a_notebook_shows_the_animation_and_the_model(tmp_path):
    """Without a path `animate` returns the page, which a notebook shows in a frame of its own
    (the page's text escaped into `srcdoc`); `save` writes it and refuses what is not a file;
    the model shows a summary table."""
    import html

    m = multibody.load("three_body")
    run = m.simulate(t_end=0.5)
    page = m.animate(run)
    frame = page._repr_html_()
    assert frame.startswith('<iframe srcdoc="') and frame.endswith("</iframe>")
    inner = frame[len('<iframe srcdoc="') : frame.index('" style=')]
    assert '"' not in inner and "<" not in inner, "the page is escaped into the attribute"
    assert html.unescape(inner) == page.html
    # The same page as one written to a file.
    m.animate(run, tmp_path / "written.html")
    assert (tmp_path / "written.html").read_text(encoding="utf-8") == page.html
    page.save(tmp_path / "saved.html")
    assert (tmp_path / "saved.html").read_text(encoding="utf-8") == page.html
    (tmp_path / "folder").mkdir()
    with pytest.raises(FileExistsError):
        page.save(tmp_path / "folder")
    (tmp_path / "link").symlink_to(tmp_path / "saved.html")
    with pytest.raises(FileExistsError):
        page.save(tmp_path / "link")
    assert (tmp_path / "saved.html").read_text(encoding="utf-8") == page.html
    # The model's table: every coordinate, the ignorable ones marked, the formulations.
    table = m._repr_html_()
    assert table.startswith("<table>")
    cells = dict(re.findall(r"<tr><th[^>]*>([^<]*)</th><td[^>]*>(.*?)</td></tr>", table))
    expected = [f"<b>{c}</b> (ignorable)" if c in m.ignorable else c for c in m.coordinates]
    assert cells["coordinates"].split(", ") == expected, cells["coordinates"]
    assert m.ignorable, "scene 2 has ignorable coordinates to mark"
    assert cells["formulations"].split(", ") == list(m.formulations)
    assert cells["model"] == "three_body"


def coverage(image):
    """The share of the picture's pixels that draw the system: a body's colour or a rod's grey
    (the white background and the light ground grid excluded)."""
    w, h = image.size
    drawn = total = 0
    for y in range(0, h, 2):
        for x in range(0, w, 2):
            r, g, b = image.getpixel((x, y))[:3]
            _, s, v = colorsys.rgb_to_hsv(r / 255, g / 255, b / 255)
            total += 1
            drawn += s > 0.35 or v < 0.45
    return drawn / total


@pytest.mark.parametrize("name", ["pendulum_on_cart_10", "three_body"])
def test_the_bodies_fill_a_fair_part_of_the_view(tmp_path, name):
    from PIL import Image

    m = multibody.pendulum_on_cart(10) if name == "pendulum_on_cart_10" else multibody.load(name)
    path, run = animated(m, tmp_path / f"{name}.html", m.formulations[-1], t_end=3.0, dt_out=0.05)
    shots = []
    for t in [0.5, 2.5]:
        url = path.as_uri() + f"#t={t}&size=800x520"
        state = page_state(tmp_path, url)
        # Every body is in the view.
        assert all(0 < x < 800 and 0 < y < 520 for x, y in state["screen"]), state["screen"]
        shot = tmp_path / f"{name}_{t}.png"
        chromium(tmp_path, f"--screenshot={shot}", url)
        image = Image.open(shot).convert("RGB").crop((0, 60, 800, 560))
        assert coverage(image) >= 0.04, (name, t, coverage(image))
        shots.append(image)
    # The system moved between the two times, and so did the picture.
    assert shots[0].tobytes() != shots[1].tobytes()


def test_the_camera_follows_a_travelling_system(tmp_path):
    m = multibody.load("bicycle")
    path, run = animated(m, tmp_path / "bicycle.html", "kane", t_end=3.0, dt_out=0.05)
    # The bicycle rides away further than its size: the camera follows its centre by default,
    # and the bodies stay in the middle of the view.
    middles = []
    for t in [0.5, 2.5]:
        state = page_state(tmp_path, path.as_uri() + f"#t={t}&size=800x520")
        assert state["follow"] is True
        xs = [p[0] for p in state["screen"]]
        middles.append(sum(xs) / len(xs))
        assert 200 < middles[-1] < 600, middles
    assert np.linalg.norm(np.subtract(state["middle"], page_state(tmp_path, path.as_uri() + "#t=0.5&size=800x520")["middle"])) > 1.0
    # Asked not to follow, the view stays put and the bicycle leaves the middle.
    fixed = [page_state(tmp_path, path.as_uri() + f"#t={t}&size=800x520&follow=0") for t in [0.5, 2.5]]
    assert fixed[0]["follow"] is False and fixed[0]["middle"] == fixed[1]["middle"]


def test_a_long_chain_s_bobs_do_not_overlap(tmp_path):
    # Point masses a link apart: each is drawn as a cube of 0.9 of its link, where a twentieth of
    # the view would make the 20-link chain's cubes overlap.
    m = multibody.pendulum_on_cart(20)
    path, run = animated(m, tmp_path / "chain.html", m.formulations[-1], t_end=1.0, dt_out=0.1)
    state = page_state(tmp_path, path.as_uri() + "#t=0.5&size=800x520")
    assert math.isclose(state["typicalLink"], m.params["l1"], rel_tol=1e-6)
    assert 2 * state["pointSize"] <= 0.9 * state["typicalLink"] * (1 + 1e-12)
    assert 2 * state["pointSize"] < 0.1 * state["extent"], "smaller than a twentieth of the view"


def test_a_trail_draws_where_a_body_has_been(tmp_path):
    from PIL import Image

    m = multibody.load("cart_pendulum")
    path, run = animated(m, tmp_path / "trail.html", "kane", t_end=3.0, dt_out=0.01)
    view = "&size=800x520&follow=0"
    now = page_state(tmp_path, path.as_uri() + "#t=3" + view + "&trail=bar2")
    assert now["trail"] == {"body": "bar2", "points": now["index"] + 1}
    assert page_state(tmp_path, path.as_uri() + "#t=3" + view)["trail"] is None
    shots = {}
    for name, extra in [("plain", ""), ("trail", "&trail=bar2")]:
        shot = tmp_path / f"{name}.png"
        chromium(tmp_path, f"--screenshot={shot}", path.as_uri() + "#t=3" + view + extra)
        shots[name] = Image.open(shot).convert("RGB")
    # Where bar2's centre was earlier (the camera does not move: follow=0), its colour shows
    # with the trail and not without, away from where the bodies are now.
    want = (30 + 2 * 137.508) % 360
    def near(hues):
        return len([h for h in hues if min(abs(h - want), 360 - abs(h - want)) < 15])
    shown = 0
    for t in [0.5, 1.0, 1.5, 2.0]:
        earlier = page_state(tmp_path, path.as_uri() + f"#t={t}" + view)
        x, y = earlier["screen"][2]
        x, y = x + earlier["offset"][0], y + earlier["offset"][1]
        if min(math.dist((x, y), p) for p in now["screen"]) < 60:
            continue
        if near(hue_at(shots["trail"], x, y, radius=3)) >= 3 and near(hue_at(shots["plain"], x, y, radius=3)) == 0:
            shown += 1
    assert shown >= 2, shown


def test_runs_overlaid_are_drawn_where_their_coordinates_put_them(tmp_path):
    from PIL import Image

    m = multibody.load("cart_pendulum")
    first = m.simulate("kane", t_end=2.0, dt_out=0.01, frame=False)
    # Another run that parts from the first: its pendulum started further out.
    other = m.simulate("lagrange", t_end=2.0, dt_out=0.01, q={"theta1": 1.2, "theta2": 1.5}, qdot={"theta1": 0.0, "theta2": 0.0, "x": 0.0}, frame=False)
    path = tmp_path / "overlaid.html"
    m.animate([first, other], path)
    l = m.params["l"]
    url = path.as_uri() + "#t=1.5&size=800x520&follow=0"
    state = page_state(tmp_path, url)
    assert [o["formulation"] for o in state["overlays"]] == ["lagrange"]
    overlay = state["overlays"][0]
    i = overlay["index"]
    assert math.isclose(other["t"][i], 1.5, abs_tol=1e-9)
    x, a, b = other["x"][i], other["theta1"][i], other["theta2"][i]
    expected = [x + l * math.sin(a) + l / 2 * math.sin(b), -l * math.cos(a) - l / 2 * math.cos(b), 0.0]
    assert np.allclose(overlay["bodies"][2]["center"], expected, atol=1e-5)
    # The bodies are the first run's, apart from the overlay's.
    assert np.linalg.norm(np.subtract(state["bodies"][2]["center"], expected)) > 0.3
    shot = tmp_path / "overlaid.png"
    chromium(tmp_path, f"--screenshot={shot}", url)
    image = Image.open(shot).convert("RGB")
    # The overlay's dot for bar2 (dark, #222222) where the page says it is.
    px, py = overlay["screen"][2]
    px, py = px + state["offset"][0], py + state["offset"][1]
    dark = [image.getpixel((int(px) + i, int(py) + j)) for i in range(-2, 3) for j in range(-2, 3)]
    assert sum(1 for r, g, b in dark if max(r, g, b) < 90) >= 10, dark


def shadowed(tmp_path, url):
    """The page at `url` shot with its shadows and without (`shots`: "shadow", "none"), their
    difference in grey, and the pixels that differ, asserting that the shadows only darken:
    every pixel that differs is darker with them."""
    from PIL import Image, ImageChops

    shots = {}
    for name, extra in [("shadow", ""), ("none", "&shadow=0")]:
        shot = tmp_path / f"{name}.png"
        chromium(tmp_path, f"--screenshot={shot}", url + extra)
        shots[name] = Image.open(shot).convert("RGB")
    diff = ImageChops.difference(shots["shadow"], shots["none"]).convert("L")
    changed = [(i, j) for j in range(diff.height) for i in range(diff.width) if diff.getpixel((i, j)) > 8]
    assert all(sum(shots["shadow"].getpixel(p)) < sum(shots["none"].getpixel(p)) for p in changed)
    return shots, diff, changed


def test_shapes_are_drawn_lit_and_cast_shadows(tmp_path):
    # cart_pendulum gives its bodies shapes: the cart a box, the bars cylinders.
    m = multibody.load("cart_pendulum")
    path, run = animated(m, tmp_path / "shapes.html", "kane", t_end=1.0, dt_out=0.05)
    url = path.as_uri() + "#t=0.5&size=800x520&follow=0"
    state = page_state(tmp_path, url)
    assert state["shaped"] == 3 and state["shadows"] > 0, state
    # Asked for the inertia boxes, no shape is drawn.
    assert page_state(tmp_path, url + "&inertia=1")["shaped"] == 0
    shots, diff, changed = shadowed(tmp_path, url)
    assert len(changed) > 300, len(changed)
    # Each body's shadow lies where its centre drops onto the ground (unless a body hides it).
    near = 0
    for x, y in state["ground"]:
        x, y = x + state["offset"][0], y + state["offset"][1]
        near += any(diff.getpixel((int(x) + di, int(y) + dj)) > 8 for di in range(-3, 4) for dj in range(-3, 4))
    assert near >= 2, (near, state["ground"])
    # Lit by a light: the cart's faces (its hue, 30 degrees) show at clearly different values.
    values = []
    image = shots["none"]
    for j in range(60, 560):
        for i in range(0, 700):
            r, g, b = image.getpixel((i, j))
            h, s, v = colorsys.rgb_to_hsv(r / 255, g / 255, b / 255)
            if s > 0.35 and min(abs(360 * h - 30), 360 - abs(360 * h - 30)) < 6:
                values.append(v)
    assert len(values) > 200 and max(values) - min(values) > 0.15, (len(values), min(values or [0]), max(values or [0]))



def test_round_shapes_take_as_many_sides_as_their_size_on_the_page(tmp_path):
    # cart_pendulum's bars are cylinders: drawn small they take fewer sides than drawn large,
    # and the triangles drawn are those sides' (a cylinder four to a side: two in its wall, one
    # in each end; the cart's box twelve).
    m = multibody.load("cart_pendulum")
    path, _ = animated(m, tmp_path / "sides.html", "kane", t_end=1.0, dt_out=0.05)
    states = [page_state(tmp_path, path.as_uri() + f"#t=0.5&size={size}&follow=0") for size in ["300x200", "1800x1200"]]
    sides = [[n for body in state["sides"] for n in body] for state in states]
    for state, counts in zip(states, sides):
        assert state["shaped"] == 3 and len(counts) == 2, state
        assert state["triangles"] == 12 + sum(4 * n for n in counts), (state["triangles"], counts)
    assert all(small < large for small, large in zip(*sides)), sides


def test_the_ground_is_where_the_lowest_solid_reaches(tmp_path):
    # The bicycle rolls on the plane z = 0, its wheels drawn as discs of radius rR and rF: the
    # ground is drawn there (under the discs' bounding spheres, which a disc 4 cm thick exceeds
    # by less than a millimetre), not a rear frame's half-diagonal below the lowest centre.
    m = multibody.load("bicycle")
    path, _ = animated(m, tmp_path / "bicycle.html", "kane", t_end=2.0, dt_out=0.02)
    state = page_state(tmp_path, path.as_uri() + "#t=1&size=800x520")
    assert state["shaped"] == 2 and -0.005 < state["groundHeight"] <= 0.0, state["groundHeight"]
    # A point mass alone (its height y, gravity along -y): its cube rests on the ground at the
    # lowest point of its run.
    m = multibody.load("bouncing_ball")
    path, run = animated(m, tmp_path / "ball.html", "kane", t_end=2.0, dt_out=0.01)
    state = page_state(tmp_path, path.as_uri() + "#t=0&size=800x520")
    lowest = float(np.min(run["y"]))
    assert abs(state["groundHeight"] - (lowest - state["pointSize"])) < 1e-9, (state["groundHeight"], lowest, state["pointSize"])


def test_the_view_moves_and_plays_faster_when_asked(tmp_path):
    m = multibody.load("cart_pendulum")
    path, run = animated(m, tmp_path / "view.html", "kane", t_end=10.0, dt_out=0.01)
    # Moved on the page (shift-drag; `&pan=` in the address): every body by the same pixels.
    still = page_state(tmp_path, path.as_uri() + "#t=1&size=800x520")
    moved = page_state(tmp_path, path.as_uri() + "#t=1&size=800x520&pan=40,-20")
    assert moved["pan"] == [40, -20]
    assert np.allclose(np.subtract(moved["screen"], still["screen"]), [[40, -20]] * 3, atol=1e-9)
    # Played at a speed, the frame shown is the last sample at or before the start plus speed
    # times the playing clock (the page records the clock it last drew at). How much time the
    # browser's virtual clock grants varies from run to run (8 to 80 ms seen); at 64 times the
    # motion's pace a page that ignored the speed would be 63 times that behind, many samples.
    long = m.simulate("kane", t_end=100.0, dt_out=0.05, frame=False)
    m.animate(long, path)
    _, state = page_dom(tmp_path, path.as_uri() + "#size=800x520&speed=64", "--virtual-time-budget=2000")
    played = state["played"]
    assert state["speed"] == 64 and played["ms"] >= 1, state
    due = played["from"] + 64 * played["ms"] / 1000
    assert due - 0.05 - 1e-9 < state["t"] <= due + 1e-9, (state["t"], due, played)


def mesh_on_an_arm(tmp_path, name, triangles, axis, arm, gravity, th0, placed):
    """`name.stl` (a text STL of `triangles`, each three points) and `name.ron`, a model whose
    arm turns about `axis` (of the world) carrying, at `arm` (three numbers) from the pivot, a
    point mass drawn as that mesh (`placed`: the Mesh's other fields) under `gravity` (three
    numbers); the model's path. Its mesh's file is named on line 6."""
    facets = "".join("facet normal 0 0 0\nouter loop\n" + "".join("vertex %.6f %.6f %.6f\n" % v for v in tri) + "endloop\nendfacet\n" for tri in triangles)
    (tmp_path / f"{name}.stl").write_text(f"solid {name}\n" + facets + f"endsolid {name}\n")
    numbers = lambda xs: ", ".join(f'"{x}"' for x in xs)
    path = tmp_path / f"{name}.ron"
    path.write_text(
        f"""Model(
        name: "{name}",
        parameters: {{ "m": 1.0, "g": 9.81 }},
        coordinates: ["th"],
        frames: [Frame(name: "arm", parent: "world", rotation: [{axis}("th")])],
        bodies: [Body(name: "{name}", frame: "arm", mass: "m", com: [{numbers(arm)}], inertia: PointMass, shape: Mesh(file: "{name}.stl", origin: [{numbers(arm)}], {placed}))],
        forces: [Gravity(vector: [{numbers(gravity)}])],
        quasi_velocities: QuasiVelocities(full: ["th'"], reduced: ["th'"]),
        initial: Initial(q: {{"th": "{th0}"}}, qdot: {{"th": "0"}}),
    )"""
    )
    return path


def test_a_mesh_is_drawn_from_every_side(tmp_path):
    # A tetrahedron as a text STL, one face wound the wrong way round (files do not all keep
    # STL's rule): drawn from both sides, all four faces reach the page, none culled.
    corners = [(0, 0, 0), (0.3, 0, 0), (0, 0.3, 0), (0, 0, 0.3)]
    faces = [(0, 2, 1), (0, 1, 3), (0, 3, 2), (1, 3, 2)]
    triangles = [[corners[k] for k in f] for f in faces]
    path = mesh_on_an_arm(tmp_path, "tetra", triangles, "Z", [1, 0, 0], [0, "-g", 0], -0.5, 'rpy: ["0.3", "0.2", "0.1"]')
    m = multibody.load(str(path))
    path, run = animated(m, tmp_path / "tetra.html", "kane", t_end=1.0, dt_out=0.05)
    state = page_state(tmp_path, path.as_uri() + "#t=0.5&size=800x520")
    assert state["shaped"] == 1 and state["triangles"] == 4 and state["shadows"] > 0, state
    # Its file gone, the model still loads and runs (a worker elsewhere has no mesh files), and
    # drawing it is refused, located at the mesh's file.
    (tmp_path / "gone.ron").write_text((tmp_path / "tetra.ron").read_text().replace("tetra.stl", "gone.stl"))
    gone = multibody.load(str(tmp_path / "gone.ron"))
    run = gone.simulate("kane", t_end=0.2, dt_out=0.05, frame=False)
    with pytest.raises(multibody.ModelError, match=r"gone\.ron:6:.*cannot be read"):
        gone.animate(run, tmp_path / "gone.html")
    assert not (tmp_path / "gone.html").exists()


def test_a_fine_mesh_casts_its_shadow_from_a_coarser_copy(tmp_path):
    # A sphere of 1,520 triangles (1,600 less the poles' collapsed ones): its shadow (its only
    # one: the rod to a body drawn as its shapes is left out), drawn from a copy of 48 triangles
    # at most where the ball is small on the page, still falls under it, where its centre drops
    # onto the ground, and only darkens.
    bands, sides = 20, 40
    at = lambda j, k: (math.sin(math.pi * j / bands) * math.cos(2 * math.pi * k / sides), math.sin(math.pi * j / bands) * math.sin(2 * math.pi * k / sides), math.cos(math.pi * j / bands))
    triangles = [tri for j in range(bands) for k in range(sides) for tri in [(at(j, k), at(j + 1, k), at(j + 1, k + 1)), (at(j, k), at(j + 1, k + 1), at(j, k + 1))]]
    path = mesh_on_an_arm(tmp_path, "ball", triangles, "Y", [0, 0, -1], [0, 0, "-g"], 0.8, 'scale: ["0.2", "0.2", "0.2"]')
    m = multibody.load(str(path))
    path, _ = animated(m, tmp_path / "ball.html", "kane", t_end=1.0, dt_out=0.05)
    # Large on the page (its radius about 60 pixels), the shadow is the mesh's own; small (about
    # 36), the coarser copy's.
    large = page_state(tmp_path, path.as_uri() + "#t=0&size=800x520&axes=0")
    url = path.as_uri() + "#t=0&size=480x312&axes=0"
    state = page_state(tmp_path, url)
    for s in (large, state):
        assert s["shaped"] == 1 and s["triangles"] == 2 * bands * sides - 2 * sides and s["shadows"] == 1, s
    assert large["shadowTriangles"] == large["triangles"] and 8 <= state["shadowTriangles"] <= 48, (large["shadowTriangles"], state["shadowTriangles"])
    _, _, changed = shadowed(tmp_path, url)
    assert len(changed) > 100, len(changed)
    # The shadow's middle is near where the ball's centre drops onto the ground.
    x, y = state["ground"][0][0] + state["offset"][0], state["ground"][0][1] + state["offset"][1]
    mx, my = sum(p[0] for p in changed) / len(changed), sum(p[1] for p in changed) / len(changed)
    assert math.hypot(mx - x, my - y) < 6, ((mx, my), (x, y))


SHELL = """
        Body(name: "shell", frame: "arm", mass: "m", com: ["1", "0", "0"], inertia: PointMass, shape: Sphere(radius: "0.5", origin: ["1", "0", "0"])),"""
NESTED = """Model(
    name: "nested",
    parameters: { "m": 1.0 },
    coordinates: ["th"],
    frames: [Frame(name: "arm", parent: "world", rotation: [Z("th")])],
    bodies: [""" + SHELL + """
        Body(name: "core", frame: "arm", mass: "m", com: ["1", "0", "0"], inertia: PointMass, shape: Box(size: ["0.3", "0.3", "0.3"], origin: ["1", "0", "0"])),
    ],
    quasi_velocities: QuasiVelocities(full: ["th'"], reduced: []),
    initial: Initial(q: {"th": "0"}, qdot: {"th": "1"}),
)"""


def hue_count(image, want, tolerance=12):
    """How many saturated pixels of `image` have a hue within `tolerance` degrees of `want`."""
    hsv = np.asarray(image.convert("HSV"), dtype=float)
    hue, saturation, value = hsv[..., 0] * 360 / 255, hsv[..., 1] / 255, hsv[..., 2] / 255
    off = np.minimum(np.abs(hue - want), 360 - np.abs(hue - want))
    return int(np.sum((saturation > 0.35) & (value > 0.15) & (off < tolerance)))


def test_a_body_inside_another_is_hidden(tmp_path):
    # Drawn in depth, not in an order of faces: a box inside a sphere shows nowhere, from any
    # side the camera takes; without the sphere it shows.
    from PIL import Image

    shell, core = 30.0, (30 + 137.508) % 360
    (tmp_path / "nested.ron").write_text(NESTED)
    # The core alone is the first body: the shell's colour.
    (tmp_path / "core.ron").write_text(NESTED.replace(SHELL, ""))
    for name in ["nested", "core"]:
        m = multibody.load(str(tmp_path / f"{name}.ron"))
        path, run = animated(m, tmp_path / f"{name}.html", "kane", t_end=2.0, dt_out=0.1)
        for t in [0.0, 1.5]:
            url = path.as_uri() + f"#t={t}&size=800x520"
            assert page_state(tmp_path, url)["webgl"] is True
            shot = tmp_path / f"{name}_{t}.png"
            chromium(tmp_path, f"--screenshot={shot}", url)
            # The stage alone (the legend, on the right, shows both colours).
            image = Image.open(shot).convert("RGB").crop((0, 60, 800, 560))
            if name == "nested":
                assert hue_count(image, shell) > 2000 and hue_count(image, core) == 0, (t, hue_count(image, shell), hue_count(image, core))
            else:
                assert hue_count(image, shell) > 500, (t, hue_count(image, shell))


def test_without_webgl_the_bodies_are_drawn_as_their_links_and_centres(tmp_path):
    from PIL import Image

    m = multibody.load("cart_pendulum")
    path, run = animated(m, tmp_path / "plain.html", "kane", t_end=1.0, dt_out=0.05)
    url = path.as_uri() + "#t=0.5&size=800x520"
    dom, state = page_dom(tmp_path, url, "--disable-webgl")
    assert state["webgl"] is False and state["shadows"] == 0
    assert "offers no WebGL" in re.search(r'<p id="notice"[^>]*>(.*?)</p>', dom, re.S).group(1)
    shot = tmp_path / "plain.png"
    chromium(tmp_path, "--disable-webgl", f"--screenshot={shot}", url)
    image = Image.open(shot).convert("RGB")
    # Each body's centre, as a dot of its colour where the page says.
    for k in range(3):
        want = (30 + k * 137.508) % 360
        px, py = state["screen"][k]
        hues = hue_at(image, px + state["offset"][0], py + state["offset"][1], radius=3)
        assert len([h for h in hues if min(abs(h - want), 360 - abs(h - want)) < 15]) >= 10, (k, hues[:10])


DRAWN = [(name, None) for name in multibody.built_in()] + [("pendulum_on_cart", 8), ("floating_chain", 4)]


@pytest.mark.parametrize("name,n", DRAWN, ids=[name if n is None else f"{name}({n})" for name, n in DRAWN])
def test_every_built_in_model_and_family_is_drawn(tmp_path, name, n):
    # In WebGL, with nothing on the console, every body in the view at two times, the bodies
    # covering a visible part of it (a lone point mass is a cube of a twentieth of the view:
    # about 0.7 % of the picture), and the picture moving between the two (a lone ball seen at
    # its own size stayed in the middle of an empty view).
    from PIL import Image

    m = multibody.load(name) if n is None else getattr(multibody, name)(n)
    path, run = animated(m, tmp_path / "page.html", m.formulations[-1], t_end=1.0, dt_out=0.05)
    shots = []
    for t in [0.2, 0.8]:
        url = path.as_uri() + f"#t={t}&size=800x520"
        state = page_state(tmp_path, url)
        assert state["webgl"] is True
        assert all(0 < x < 800 and 0 < y < 520 for x, y in state["screen"]), (name, t, state["screen"])
        shot = tmp_path / f"page_{t}.png"
        chromium(tmp_path, f"--screenshot={shot}", url)
        shots.append(Image.open(shot).convert("RGB").crop((0, 60, 800, 560)))
        assert coverage(shots[-1]) >= 0.005, (name, t, coverage(shots[-1]))
    assert shots[0].tobytes() != shots[1].tobytes(), name


def test_the_frames_axes_can_be_left_out(tmp_path):
    # `&axes=0` (the Axes box): the frames' axes (x red, y green, z blue, over the bodies) are
    # not drawn; the world's axes, under the bodies, still are.
    from PIL import Image

    m = multibody.load("cart_pendulum")
    path, run = animated(m, tmp_path / "axes.html", "kane", t_end=1.0, dt_out=0.05)
    counts = {}
    for name, extra in [("shown", ""), ("left out", "&axes=0")]:
        url = path.as_uri() + "#t=0.5&size=800x520&follow=0" + extra
        assert page_state(tmp_path, url)["axes"] is (name == "shown")
        shot = tmp_path / f"{name}.png"
        chromium(tmp_path, f"--screenshot={shot}", url)
        image = Image.open(shot).convert("RGB").crop((0, 60, 800, 560))
        # The axes' green and blue (the bodies' hues are 30, 167.5 and 305 degrees).
        counts[name] = [hue_count(image, 120, 8), hue_count(image, 205, 8)]
    assert all(shown > left + 20 and left > 0 for shown, left in zip(counts["shown"], counts["left out"])), counts
