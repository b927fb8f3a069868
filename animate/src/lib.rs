//! The motion shown: a trajectory written as one self-contained HTML page that plays it in 3-D
//! (its scripts and data inside, no network needed; the solids drawn in WebGL by three.js), each
//! body as the shapes the model gives it or as its equivalent inertia box (the uniform box with
//! the body's mass and principal moments, along its principal axes; a point mass as a small
//! cube), each frame as its axes, with a time slider, play/pause and the time shown. The command line's `simulate --animate OUT.html` and the Python wheel's
//! `Model.animate` write it.
//!
//! ```
//! let model = generator::model::load(concat!(env!("CARGO_MANIFEST_DIR"), "/../models/cart_pendulum.ron")).unwrap();
//! let params: Vec<f64> = model.parameters.iter().map(|(_, v)| *v).collect();
//! let motion = animate::Motion { formulation: "kane", times: &[0.0, 0.1], q: &[0.0, 0.0, 0.0, 0.1, 0.0, 0.2] };
//! let html = animate::page(&model, &params, &motion).unwrap();
//! assert!(html.starts_with("<!DOCTYPE html>") && !html.contains("/*DATA*/"));
//! ```

use generator::model::Model;
use generator::pose::Poser;
use nalgebra::{Matrix3, SymmetricEigen};

/// The page's template: its script reads the JSON the writer puts in place of `/*DATA*/`, and
/// draws with the three.js that goes in place of `/*THREE*/`.
const TEMPLATE: &str = include_str!("page.html");

/// three.js, the parts the page uses, bundled and minified (`animate/three/build.sh` makes it
/// from the versions `animate/three/package.json` pins; MIT license, its notice inside).
const THREE: &str = include_str!("three.min.js");

/// A run to show: its output times and the coordinates at each, row-major (`times.len()` rows
/// of the model's coordinates).
pub struct Motion<'a> {
    pub formulation: &'a str,
    pub times: &'a [f64],
    pub q: &'a [f64],
}

/// Why no page was written.
#[derive(Debug, thiserror::Error)]
pub enum AnimateError {
    #[error("the motion has {rows} rows of {got} values for {times} times; the model has {expected} coordinates")]
    Shape { rows: usize, got: usize, times: usize, expected: usize },
    #[error("the motion has no samples")]
    Empty,
    #[error("the model's kinematics cannot be evaluated: {0}")]
    Evaluate(#[from] generator::symbolic::EvalError),
    #[error("a coordinate is not finite at t = {t}: nothing to draw there")]
    NotFinite { t: f64 },
    #[error(transparent)]
    File(#[from] files::FileError),
    /// A mesh the model draws could not be read ([`Model::undrawable`]).
    #[error("{0}")]
    Mesh(Box<generator::model::ModelError>),
}

/// A body's box: half-extents along its principal axes (columns of `axes`, row-major, in its
/// frame), from its principal moments: a box of sides `a, b, c` and mass `m` has
/// `I_a = m (b^2 + c^2) / 12`, so `a^2 = 6 (I_b + I_c - I_a) / m`.
///
/// ```
/// // A uniform rod along x: 1 kg, 2 m long, I = m L^2 / 12 about y and z.
/// let (half, _) = animate::inertia_box(1.0, &[0.0, 0.0, 0.0, 0.0, 1.0 / 3.0, 0.0, 0.0, 0.0, 1.0 / 3.0]);
/// assert!((half[0] - 1.0).abs() < 1e-12 && half[1] < 1e-6 && half[2] < 1e-6);
/// ```
pub fn inertia_box(mass: f64, inertia: &[f64; 9]) -> ([f64; 3], [f64; 9]) {
    let m = Matrix3::from_row_slice(inertia);
    let eigen = SymmetricEigen::new(m);
    let moments = eigen.eigenvalues;
    let half: [f64; 3] = std::array::from_fn(|k| {
        let (a, b, c) = (moments[k], moments[(k + 1) % 3], moments[(k + 2) % 3]);
        let side2 = 6.0 * (b + c - a) / mass.max(f64::MIN_POSITIVE);
        side2.max(0.0).sqrt() / 2.0
    });
    let v = eigen.eigenvectors;
    (half, std::array::from_fn(|k| v[(k / 3, k % 3)]))
}

/// The most mesh triangles a page carries, all meshes together: each costs about 60 bytes of
/// the page, so a robot's meshes of hundreds of thousands of triangles share 20,000 (1.2 MB),
/// which WebGL draws in a few milliseconds (docs/benchmarks/page.json has the frame rate).
const MAX_PAGE_MESH_TRIANGLES: usize = 20_000;

/// The meshes of `poser` (its bodies' and its scenery's) simplified further where they hold
/// more than `total` triangles together: each mesh keeps a share in proportion to its scaled
/// bounding box's surface (a large part more than a small one), 12 at least.
fn share_mesh_triangles(poser: &mut generator::pose::Poser, total: usize) {
    let shapes = || poser.bodies.iter().flat_map(|b| b.shapes.iter()).chain(poser.scenery.iter());
    let count: usize = shapes().filter_map(|s| s.mesh.as_ref()).map(|m| m.triangles.len()).sum();
    if count <= total {
        return;
    }
    let surface = |s: &generator::pose::ShapeValues| {
        let (lo, hi) = s.mesh.as_ref().map_or(([0.0; 3], [0.0; 3]), |m| m.bounds());
        let d: [f64; 3] = std::array::from_fn(|i| ((hi[i] - lo[i]) * s.sizes[i]).abs());
        d[0] * d[1] + d[1] * d[2] + d[2] * d[0]
    };
    let all: f64 = shapes().filter(|s| s.mesh.is_some()).map(surface).sum();
    // Solids beside the meshes keep their shapes (a cylinder's sizes are two, not a mesh's
    // three scale factors).
    let shapes = poser.bodies.iter_mut().flat_map(|b| b.shapes.iter_mut()).chain(poser.scenery.iter_mut()).filter(|s| s.mesh.is_some());
    for s in shapes {
        let share = if all > 0.0 { surface(s) / all } else { 0.0 };
        let keep = ((total as f64 * share) as usize).max(12);
        if let Some(mesh) = &s.mesh
            && mesh.triangles.len() > keep
        {
            s.mesh = Some(std::sync::Arc::new(mesh.simplified(keep)));
        }
    }
}

/// A mesh's vertices scaled by `sizes` along its axes.
fn scaled<'a>(mesh: &'a generator::model::TriangleMesh, sizes: &'a [f64]) -> impl Iterator<Item = [f64; 3]> + 'a {
    mesh.vertices.iter().map(|v| std::array::from_fn(|i| v[i] * sizes[i]))
}

/// The most triangles a small mesh's shadow is drawn with (the page chooses where): a copy of
/// the mesh simplified to them. A shadow is an outline on the ground, and where WebGL is drawn in
/// software every triangle costs twice, once for the solid and once for its shadow (docs/tool.md
/// has the frame rates).
const SHADOW_TRIANGLES: usize = 48;

/// A shape as the page reads it: its solid, sizes and placement; a mesh's scaled vertices and
/// its triangles, flat, and (where it has more than [`SHADOW_TRIANGLES`]) its shadow's, as
/// `shadow`.
fn shape_json(s: &generator::pose::ShapeValues) -> serde_json::Value {
    let mut json = serde_json::json!({ "solid": s.solid, "sizes": s.sizes, "o": s.origin, "r": s.rotation });
    if let Some(m) = &s.mesh {
        let flat = |m: &generator::model::TriangleMesh| {
            let points: Vec<serde_json::Value> = scaled(m, &s.sizes).flatten().map(compact).collect();
            (points, m.triangles.iter().flatten().copied().collect::<Vec<u32>>())
        };
        let (points, triangles) = flat(m);
        json["points"] = points.into();
        json["triangles"] = triangles.into();
        if m.triangles.len() > SHADOW_TRIANGLES {
            let (points, triangles) = flat(&m.simplified(SHADOW_TRIANGLES));
            json["shadow"] = serde_json::json!({ "points": points, "triangles": triangles });
        }
    }
    json
}

/// How far a shape reaches from `center` (in the body's frame): its origin's distance plus the
/// radius of the sphere that holds it.
fn shape_reach(s: &generator::pose::ShapeValues, center: &[f64; 3]) -> f64 {
    let bound = match s.solid {
        "box" => 0.5 * s.sizes.iter().map(|x| x * x).sum::<f64>().sqrt(),
        "sphere" => s.sizes[0],
        "mesh" => s.mesh.iter().flat_map(|m| scaled(m, &s.sizes)).map(|p| (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt()).fold(0.0, f64::max),
        // A capsule's radius beyond its length along its axis; a cylinder's rim's corner.
        "capsule" => s.sizes[0] + 0.5 * s.sizes[1],
        _ => s.sizes[0].hypot(0.5 * s.sizes[1]),
    };
    let d = (0..3).map(|i| (s.origin[i] - center[i]).powi(2)).sum::<f64>().sqrt();
    d + bound
}

/// The page showing `motion` of `model` with parameters `params` (the model's order).
pub fn page(model: &Model, params: &[f64], motion: &Motion<'_>) -> Result<String, AnimateError> {
    page_overlaid(model, params, std::slice::from_ref(motion))
}

/// The page showing the first of `motions` as [`page`] does, and each other one over it: its
/// links and its bodies' centres in a colour of its own, at the time shown (the four
/// formulations of `multibody compare --animate`, to see them part at loose tolerances).
///
/// ```
/// let model = generator::model::load(concat!(env!("CARGO_MANIFEST_DIR"), "/../models/cart_pendulum.ron")).unwrap();
/// let params: Vec<f64> = model.parameters.iter().map(|(_, v)| *v).collect();
/// let (times, a, b) = ([0.0, 0.1], [0.0, 0.0, 0.0, 0.1, 0.0, 0.2], [0.0, 0.0, 0.0, 0.1, 0.05, 0.2]);
/// let kane = animate::Motion { formulation: "kane", times: &times, q: &a };
/// let lagrange = animate::Motion { formulation: "lagrange", times: &times, q: &b };
/// let html = animate::page_overlaid(&model, &params, &[kane, lagrange]).unwrap();
/// assert!(html.contains(r#""overlays":[{"centers":null,"formulation":"lagrange""#));
/// ```
pub fn page_overlaid(model: &Model, params: &[f64], motions: &[Motion<'_>]) -> Result<String, AnimateError> {
    if let Some(e) = model.undrawable() {
        return Err(AnimateError::Mesh(Box::new(e.clone())));
    }
    let mut poser = Poser::new(model, params)?;
    share_mesh_triangles(&mut poser, MAX_PAGE_MESH_TRIANGLES);
    let Some((motion, others)) = motions.split_first() else { return Err(AnimateError::Empty) };
    let (poses, centers) = sampled(model, &poser, motion)?;
    let overlays = others
        .iter()
        .map(|o| {
            let (poses, centers) = sampled(model, &poser, o)?;
            Ok(serde_json::json!({ "formulation": o.formulation, "times": o.times, "poses": poses, "centers": centers }))
        })
        .collect::<Result<Vec<_>, AnimateError>>()?;
    let bodies: Vec<serde_json::Value> = poser
        .bodies
        .iter()
        .map(|b| {
            let (half, axes, point) = match &b.inertia {
                Some(i) if i.iter().any(|x| *x != 0.0) => {
                    let (half, axes) = inertia_box(b.mass, i);
                    // A body thin along an axis (a rod) keeps a twentieth of its largest extent.
                    let largest = half.iter().fold(0.0f64, |a, h| a.max(*h));
                    (half.map(|h| h.max(0.05 * largest)), axes, false)
                }
                _ => ([0.0; 3], [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0], true),
            };
            // A body drawn as its shapes: its size is the farthest reach of a shape from its
            // centre of mass (the page frames the view with it).
            let reach = b.shapes.iter().fold(0.0f64, |m, s| m.max(shape_reach(s, &b.com)));
            let shapes: Vec<serde_json::Value> = b.shapes.iter().map(shape_json).collect();
            serde_json::json!({ "name": b.name, "frame": b.frame, "center": b.com, "half": half, "axes": axes, "point": point, "shapes": shapes, "reach": reach })
        })
        .collect();
    // The vertical of the drawing: against gravity where the model has it, else z.
    let up = match poser.gravity {
        Some(g) if g[1].abs() > g[2].abs() && g[1].abs() >= g[0].abs() => 1,
        _ => 2,
    };
    let data = serde_json::json!({
        "model": model.name,
        "formulation": motion.formulation,
        "times": motion.times,
        "frames": poser.frame_names,
        // Each frame's parent (the world is 0; the world itself has none): the page draws the
        // links between them.
        "parents": model.frames.iter().map(|f| f.joint.as_ref().map(|j| j.parent)).collect::<Vec<_>>(),
        "bodies": bodies,
        "poses": poses,
        "centers": centers,
        "up": up,
        "gravity": poser.gravity,
        "overlays": overlays,
        "scenery": poser.scenery.iter().map(shape_json).collect::<Vec<_>>(),
    });
    Ok(assembled(&script_json(&data)))
}

/// The template with three.js and `data` in their places, written once into one string (the
/// page is mostly three.js: replacing place after place copied it each time).
fn assembled(data: &str) -> String {
    let (head, rest) = TEMPLATE.split_once("/*DATA*/").expect("the template has a place for the data");
    let (middle, tail) = rest.split_once("/*THREE*/").expect("the template has a place for three.js after the data");
    let mut page = String::with_capacity(TEMPLATE.len() + THREE.len() + data.len());
    for piece in [head, data, middle, THREE, tail] {
        page.push_str(piece);
    }
    page
}

/// `value` as JSON to put inside a script element: `</` would end the element, so it is written
/// `<\/`, and `/*` (the template's places, which a name could otherwise imitate) `/\u002a`: the
/// same strings to the script.
fn script_json(value: &serde_json::Value) -> String {
    serde_json::to_string(value).expect("plain data").replace("</", "<\\/").replace("/*", "/\\u002a")
}

/// `page` (as [`page`] made it) made live for `multibody watch`: it asks `status?token=TOKEN`
/// beside it for news (`{"run": N, "error": null or text}`), shows the error, and reloads on
/// another run than `run`, keeping its camera and time. `None` for text that is not such a page.
///
/// ```
/// let model = generator::model::load(concat!(env!("CARGO_MANIFEST_DIR"), "/../models/cart_pendulum.ron")).unwrap();
/// let params: Vec<f64> = model.parameters.iter().map(|(_, v)| *v).collect();
/// let q = vec![0.0; model.coordinates.len()];
/// let page = animate::page(&model, &params, &animate::Motion { formulation: "kane", times: &[0.0], q: &q }).unwrap();
/// let served = animate::live(&page, 3, "a1b2").unwrap();
/// assert!(served.contains(r#"const live = {"run":3,"token":"a1b2"};"#));
/// assert!(animate::live("<html></html>", 3, "a1b2").is_none());
/// ```
pub fn live(page: &str, run: u64, token: &str) -> Option<String> {
    const PLACE: &str = "/*LIVE*/null";
    if page.matches(PLACE).count() != 1 {
        return None;
    }
    Some(page.replacen(PLACE, &script_json(&serde_json::json!({ "run": run, "token": token })), 1))
}

/// Each frame's pose (origin, then rotation row-major) at each sample of `motion`, and, where a
/// centre of mass moves with the coordinates (a mass sliding on a boom), every body's centre
/// (else `None`: the page reads each body's fixed centre).
type Sampled = (Vec<Vec<Vec<serde_json::Value>>>, Option<Vec<Vec<[serde_json::Value; 3]>>>);

fn sampled(model: &Model, poser: &Poser, motion: &Motion<'_>) -> Result<Sampled, AnimateError> {
    let m = model.coordinates.len();
    let rows = motion.times.len();
    if rows == 0 {
        return Err(AnimateError::Empty);
    }
    if motion.q.len() != rows * m {
        return Err(AnimateError::Shape { rows, got: motion.q.len() / rows.max(1), times: rows, expected: m });
    }
    let moving = poser.bodies.iter().any(|b| b.moving);
    let (mut poses, mut centers) = (Vec::with_capacity(rows), Vec::new());
    for (i, &t) in motion.times.iter().enumerate() {
        let q = &motion.q[i * m..(i + 1) * m];
        if !q.iter().all(|x| x.is_finite()) {
            return Err(AnimateError::NotFinite { t });
        }
        let frames = poser.frames_at(t, q)?;
        poses.push(frames.iter().map(|p| p.origin.iter().chain(&p.rotation).map(|x| compact(*x)).collect::<Vec<_>>()).collect::<Vec<_>>());
        if moving {
            centers.push(poser.centers_at(t, q)?.iter().map(|c| c.map(compact)).collect::<Vec<_>>());
        }
    }
    Ok((poses, moving.then_some(centers)))
}

/// A float with the digits a drawing needs (single precision's shortest round trip).
fn compact(x: f64) -> serde_json::Value {
    let short: f64 = format!("{}", x as f32).parse().expect("a float prints as a float");
    serde_json::Value::from(short)
}

/// [`page`], written to `path` atomically (through an exclusive temporary file; never over what
/// is not a regular file).
pub fn write(path: &std::path::Path, model: &Model, params: &[f64], motion: &Motion<'_>) -> Result<(), AnimateError> {
    write_overlaid(path, model, params, std::slice::from_ref(motion))
}

/// [`page_overlaid`], written as [`write`] writes.
pub fn write_overlaid(path: &std::path::Path, model: &Model, params: &[f64], motions: &[Motion<'_>]) -> Result<(), AnimateError> {
    let html = page_overlaid(model, params, motions)?;
    files::write_creating_folder(path, html.as_bytes())?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cart_pendulum() -> (Model, Vec<f64>) {
        let model = generator::model::load(concat!(env!("CARGO_MANIFEST_DIR"), "/../models/cart_pendulum.ron")).unwrap();
        let params = model.parameters.iter().map(|(_, v)| *v).collect();
        (model, params)
    }

    /// The box of a body is its inertia's: its principal moments come back from the box.
    #[test]
    fn the_box_has_the_bodys_moments() {
        let inertia = [2.0, 0.3, 0.0, 0.3, 1.5, 0.1, 0.0, 0.1, 1.2];
        let mass = 3.0;
        let (half, axes) = inertia_box(mass, &inertia);
        let side: Vec<f64> = half.iter().map(|h| 2.0 * h).collect();
        let moments = [(side[1].powi(2) + side[2].powi(2)), (side[0].powi(2) + side[2].powi(2)), (side[0].powi(2) + side[1].powi(2))].map(|s| mass * s / 12.0);
        // R diag(moments) R^T is the inertia.
        let r = Matrix3::from_row_slice(&axes);
        let back = r * Matrix3::from_diagonal(&nalgebra::Vector3::from(moments)) * r.transpose();
        for k in 0..9 {
            assert!((back[(k / 3, k % 3)] - inertia[k]).abs() < 1e-12, "{back}");
        }
    }

    /// A name that would end the script element reaches the page as data.
    #[test]
    fn a_name_cannot_end_the_script() {
        let (model, params) = cart_pendulum();
        let html = page(&model, &params, &Motion { formulation: "</script><script>alert(1)</script>", times: &[0.0], q: &[0.0; 3] }).unwrap();
        assert!(!html.contains("</script><script>alert(1)"));
        assert!(html.contains(r"<\/script><script>alert(1)<\/script>"));
        assert_eq!(html.matches("</script>").count(), TEMPLATE.matches("</script>").count());
    }

    /// A name that imitates the template's places (`/*LIVE*/null`, where `watch` makes the page
    /// live) reaches the page as data: three.js is in it once and the page can still be served.
    #[test]
    fn a_name_cannot_take_a_place_of_the_template() {
        let (model, params) = cart_pendulum();
        let html = page(&model, &params, &Motion { formulation: "/*LIVE*/null /*THREE*/ /*DATA*/", times: &[0.0], q: &[0.0; 3] }).unwrap();
        assert_eq!(html.matches("/*LIVE*/null").count(), 1);
        assert_eq!(html.matches(THREE).count(), 1);
        assert!(html.contains(r#""formulation":"/\u002aLIVE*/null /\u002aTHREE*/ /\u002aDATA*/""#), "{html:.200}");
        let served = live(&html, 7, "abc").unwrap();
        assert!(served.contains(r#"const live = {"run":7,"token":"abc"};"#));
    }

    /// A centre of mass that moves with a coordinate (scene 3's tip sliding along its boom,
    /// `l/2 + rho`) is drawn where it is at every sample.
    #[test]
    fn a_sliding_mass_is_drawn_where_it_is() {
        let model = generator::model::load(concat!(env!("CARGO_MANIFEST_DIR"), "/../models/satellite_boom.ron")).unwrap();
        let params: Vec<f64> = model.parameters.iter().map(|(_, v)| *v).collect();
        let l = params[model.parameters.iter().position(|(p, _)| p.name() == "l").unwrap()];
        let mut q = vec![0.0; 14];
        (q[3], q[10]) = (0.5, 1.25);
        let html = page(&model, &params, &Motion { formulation: "kane", times: &[0.0, 1.0], q: &q }).unwrap();
        let json = html.split(r#"id="data">"#).nth(1).unwrap().split("</script>").next().unwrap();
        let data: serde_json::Value = serde_json::from_str(json).unwrap();
        let tip = data["bodies"].as_array().unwrap().iter().position(|b| b["name"] == "tip").unwrap();
        for (i, rho) in [0.5, 1.25].into_iter().enumerate() {
            let x = data["centers"][i][tip][0].as_f64().unwrap();
            assert!((x - (l / 2.0 + rho)).abs() < 1e-6, "sample {i}: {x}");
        }
        // A model whose centres stay put carries none.
        let (model, params) = cart_pendulum();
        assert!(!page(&model, &params, &Motion { formulation: "kane", times: &[0.0], q: &[0.0; 3] }).unwrap().contains("\"centers\":["));
    }

    /// A body's shapes reach the page with their sizes evaluated at the run's parameters (a bar
    /// `l` long is drawn `l` long), and a body without one has none (its inertia box is drawn).
    #[test]
    fn shapes_are_drawn_at_the_runs_parameters() {
        let (model, mut params) = cart_pendulum();
        let l = model.parameters.iter().position(|(p, _)| p.name() == "l").unwrap();
        params[l] = 1.7;
        let html = page(&model, &params, &Motion { formulation: "kane", times: &[0.0], q: &[0.0; 3] }).unwrap();
        let json = html.split(r#"id="data">"#).nth(1).unwrap().split("</script>").next().unwrap();
        let data: serde_json::Value = serde_json::from_str(json).unwrap();
        let bar1 = &data["bodies"][1]["shapes"][0];
        assert_eq!(bar1["solid"], "cylinder");
        assert_eq!(bar1["sizes"], serde_json::json!([0.03, 1.7]));
        assert!((bar1["o"][1].as_f64().unwrap() + 0.85).abs() < 1e-15, "{bar1}");
        // Reaching from the centre of mass (the rod's middle): half its length and a bit.
        let reach = data["bodies"][1]["reach"].as_f64().unwrap();
        assert!(reach > 0.85 && reach < 0.9, "{reach}");
        let model = generator::model::load(concat!(env!("CARGO_MANIFEST_DIR"), "/../models/three_body.ron")).unwrap();
        let params: Vec<f64> = model.parameters.iter().map(|(_, v)| *v).collect();
        let q = vec![0.0; model.coordinates.len()];
        let html = page(&model, &params, &Motion { formulation: "kane", times: &[0.0], q: &q }).unwrap();
        assert!(html.contains(r#""shapes":[]"#) && !html.contains(r#""solid""#));
    }

    /// Meshes that hold more triangles together than a page draws share them in proportion to
    /// their sizes: a sphere twice as wide keeps more; every mesh keeps some; the total holds.
    #[test]
    fn meshes_share_the_pages_triangles_by_size() {
        let dir = tempfile::tempdir().unwrap();
        let (bands, sides) = (40, 80);
        let at = |j: usize, k: usize| {
            let (a, b) = (std::f64::consts::PI * j as f64 / bands as f64, std::f64::consts::TAU * k as f64 / sides as f64);
            format!("vertex {} {} {}\n", a.sin() * b.cos(), a.sin() * b.sin(), a.cos())
        };
        let mut stl = String::from("solid s\n");
        for j in 0..bands {
            for k in 0..sides {
                for t in [[(j, k), (j + 1, k), (j + 1, k + 1)], [(j, k), (j + 1, k + 1), (j, k + 1)]] {
                    stl += "facet normal 0 0 0\nouter loop\n";
                    for (a, b) in t {
                        stl += &at(a, b);
                    }
                    stl += "endloop\nendfacet\n";
                }
            }
        }
        std::fs::write(dir.path().join("sphere.stl"), stl + "endsolid s\n").unwrap();
        // Eight small spheres and one twice as wide: 9 x 6,400 triangles, more than the page's
        // 20,000; beside them a body drawn as a cylinder and one as a sphere, whose sizes are
        // not a mesh's scale.
        let mut bodies: Vec<String> = (0..9)
            .map(|k| {
                let r = if k == 8 { "0.2" } else { "0.1" };
                format!(r#"Body(name: "b{k}", frame: "disk", mass: "1", com: ["{k}", "0", "0"], inertia: PointMass, shape: Mesh(file: "sphere.stl", scale: ["{r}", "{r}", "{r}"], origin: ["{k}", "0", "0"]))"#)
            })
            .collect();
        bodies.push(
            r#"Body(name: "rod", frame: "disk", mass: "1", com: ["0", "1", "0"], inertia: PointMass, shape: Cylinder(radius: "0.05", length: "1"))"#.into(),
        );
        bodies.push(r#"Body(name: "ball", frame: "disk", mass: "1", com: ["0", "2", "0"], inertia: PointMass, shape: Sphere(radius: "0.1"))"#.into());
        let ron = format!(
            r#"Model(name: "spheres", parameters: {{}}, coordinates: ["th"], frames: [Frame(name: "disk", parent: "world", rotation: [Z("th")])],
            bodies: [{}], quasi_velocities: QuasiVelocities(full: ["th'"], reduced: ["th'"]), initial: Initial(q: {{"th": "0"}}, qdot: {{"th": "1"}}))"#,
            bodies.join(", ")
        );
        std::fs::write(dir.path().join("spheres.ron"), ron).unwrap();
        let model = generator::model::load(dir.path().join("spheres.ron")).unwrap();
        let html = page(&model, &[], &Motion { formulation: "kane", times: &[0.0], q: &[0.0] }).unwrap();
        let data: serde_json::Value = serde_json::from_str(html.split(r#"id="data">"#).nth(1).unwrap().split("</script>").next().unwrap()).unwrap();
        let kept: Vec<usize> = (0..9).map(|k| data["bodies"][k]["shapes"][0]["triangles"].as_array().unwrap().len() / 3).collect();
        assert!(kept.iter().sum::<usize>() <= MAX_PAGE_MESH_TRIANGLES, "{kept:?}");
        assert!(kept[..8].iter().all(|n| *n >= 12 && *n == kept[0]) && kept[8] > 2 * kept[0], "{kept:?}");
        assert_eq!(data["bodies"][9]["shapes"][0]["sizes"], serde_json::json!([0.05, 1.0]));
        assert_eq!(data["bodies"][10]["shapes"][0]["sizes"], serde_json::json!([0.1]));
        // Each mesh's shadow is a coarser copy: at most SHADOW_TRIANGLES triangles, some, on
        // vertices inside the mesh's own bounds (scaled as the mesh is); a solid has none.
        for k in 0..9 {
            let shape = &data["bodies"][k]["shapes"][0];
            let numbers = |v: &serde_json::Value| v.as_array().unwrap().iter().map(|x| x.as_f64().unwrap()).collect::<Vec<f64>>();
            let (points, shadow) = (numbers(&shape["points"]), numbers(&shape["shadow"]["points"]));
            let triangles = shape["shadow"]["triangles"].as_array().unwrap();
            assert!(triangles.len() / 3 <= SHADOW_TRIANGLES && triangles.len() / 3 >= 8, "{k}: {}", triangles.len() / 3);
            assert!(triangles.iter().all(|v| (v.as_u64().unwrap() as usize) < shadow.len() / 3));
            for d in 0..3 {
                let axis = |p: &[f64]| p.iter().skip(d).step_by(3).fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), x| (lo.min(*x), hi.max(*x)));
                let ((lo, hi), (slo, shi)) = (axis(&points), axis(&shadow));
                assert!(slo >= lo - 1e-9 && shi <= hi + 1e-9 && shi - slo > 0.5 * (hi - lo), "{k}, axis {d}: [{slo}, {shi}] in [{lo}, {hi}]");
            }
        }
        assert!(data["bodies"][9]["shapes"][0].get("shadow").is_none() && data["bodies"][10]["shapes"][0].get("shadow").is_none());
    }

    /// The wrong shape, no samples or a NaN is refused, naming why.
    #[test]
    fn bad_motions_are_refused() {
        let (model, params) = cart_pendulum();
        let e = page(&model, &params, &Motion { formulation: "kane", times: &[0.0, 1.0], q: &[0.0; 5] }).unwrap_err();
        assert!(matches!(e, AnimateError::Shape { expected: 3, .. }), "{e}");
        assert!(matches!(page(&model, &params, &Motion { formulation: "kane", times: &[], q: &[] }), Err(AnimateError::Empty)));
        let e = page(&model, &params, &Motion { formulation: "kane", times: &[0.0, 0.5], q: &[0.0, 0.0, 0.0, f64::NAN, 0.0, 0.0] }).unwrap_err();
        assert!(matches!(e, AnimateError::NotFinite { t: 0.5 }), "{e}");
    }
}
