//! A solid given as a triangle mesh: read from an STL (binary or text), COLLADA (`.dae`) or
//! Wavefront OBJ file by the `mesh-loader` crate (made for robots' meshes: it reads what URDF
//! files name), and simplified to at most a few hundred triangles for drawing,
//! deterministically.
//!
//! A COLLADA file's `<unit>` scales it, its nodes' transforms place its parts, and its
//! `<up_axis>` is not applied: RViz, for which robots' meshes are made, does not apply it either
//! (ros-visualization/rviz#1045), so a `Y_UP` file draws as it does there.

/// The most triangles a mesh keeps when read ([`TriangleMesh::simplified`]): the page carries a
/// total for all of a model's meshes (the animation's own bound, 20,000), so a finer mesh would
/// only cost memory and reading time.
pub const MAX_DRAWN_TRIANGLES: usize = 4000;

/// The most bytes a mesh file may hold (64 MiB: a scanned part of a million triangles).
pub const MAX_MESH_BYTES: u64 = 64 << 20;

/// Why a mesh file could not be drawn.
#[derive(Debug)]
pub enum MeshError {
    /// It could not be read, or holds more than [`MAX_MESH_BYTES`].
    Read(files::FileError),
    /// It is not a mesh of its format, or its extension names none we read
    /// ([`TriangleMesh::from_bytes`]'s reason).
    Format(String),
}

/// The formats a mesh file may have, by its extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MeshFormat {
    /// `.stl`, binary or text.
    Stl,
    /// `.dae`.
    Collada,
    /// `.obj`.
    Obj,
}

/// The extensions a mesh file may have, as a sentence names them.
pub const MESH_EXTENSIONS: &str = "`.stl`, `.dae` or `.obj`";

impl MeshFormat {
    /// The format a file's extension names (any case), if one we read.
    ///
    /// ```
    /// use generator::model::MeshFormat;
    /// assert_eq!(MeshFormat::of(std::path::Path::new("link1.DAE")), Some(MeshFormat::Collada));
    /// assert_eq!(MeshFormat::of(std::path::Path::new("hand.glb")), None);
    /// ```
    pub fn of(path: &std::path::Path) -> Option<MeshFormat> {
        match path.extension()?.to_str()?.to_ascii_lowercase().as_str() {
            "stl" => Some(MeshFormat::Stl),
            "dae" => Some(MeshFormat::Collada),
            "obj" => Some(MeshFormat::Obj),
            _ => None,
        }
    }

    fn name(self) -> &'static str {
        match self {
            MeshFormat::Stl => "an STL",
            MeshFormat::Collada => "a COLLADA",
            MeshFormat::Obj => "an OBJ",
        }
    }
}

/// A mesh file's size and modification time: read again when either changes.
type Stamp = (u64, Option<std::time::SystemTime>);

/// The meshes read, oldest first: at most [`KEPT_MESHES`].
static READ: std::sync::Mutex<Vec<(std::path::PathBuf, Stamp, std::sync::Arc<TriangleMesh>)>> = std::sync::Mutex::new(Vec::new());

/// The most meshes kept read: a few robots' worth (a robot has tens), each at most
/// [`MAX_DRAWN_TRIANGLES`] (about 100 KB), so that a process that loads robot after robot (a
/// notebook, `watch`) keeps some megabytes, not every mesh it ever read.
const KEPT_MESHES: usize = 256;

/// The mesh of the file at `path` (its format by its extension, [`MeshFormat::of`]),
/// simplified for drawing ([`MAX_DRAWN_TRIANGLES`]).
/// A file is read once per process while its size and modification time stay the same (and
/// while it is among the [`KEPT_MESHES`] last read): a URDF is checked, then built, and `watch`
/// rebuilds a model on every save, and a robot's meshes can be tens of megabytes.
pub fn drawn_mesh(path: &std::path::Path) -> Result<std::sync::Arc<TriangleMesh>, MeshError> {
    // Keyed by the canonical path: a URDF names a file through `..` one way, the model another.
    let path = &std::fs::canonicalize(path).unwrap_or_else(|_| path.to_path_buf());
    let stamp: Option<Stamp> = std::fs::metadata(path).ok().map(|m| (m.len(), m.modified().ok()));
    // A poisoned lock only means another thread panicked while holding it; the list stays valid.
    let mut read = READ.lock().unwrap_or_else(|e| e.into_inner());
    if let Some((_, _, mesh)) = read.iter().find(|(p, s, _)| p == path && stamp.as_ref() == Some(s)) {
        return Ok(mesh.clone());
    }
    drop(read);
    let format = MeshFormat::of(path).ok_or_else(|| MeshError::Format(format!("its extension is not {MESH_EXTENSIONS}, the mesh formats read")))?;
    let bytes = files::read_bounded(path, MAX_MESH_BYTES).map_err(MeshError::Read)?;
    let mesh = std::sync::Arc::new(TriangleMesh::from_bytes(&bytes, format).map_err(MeshError::Format)?.simplified(MAX_DRAWN_TRIANGLES));
    if let Some(stamp) = stamp {
        read = READ.lock().unwrap_or_else(|e| e.into_inner());
        read.retain(|(p, _, _)| p != path);
        if read.len() >= KEPT_MESHES {
            let excess = read.len() + 1 - KEPT_MESHES;
            read.drain(..excess);
        }
        read.push((path.to_path_buf(), stamp, mesh.clone()));
    }
    Ok(mesh)
}

/// A triangle mesh in its file's own units and axes: vertices, and triangles as indices into
/// them, counter-clockwise seen from outside (the formats' rule; the page lights both sides, so
/// a file that breaks the rule still draws).
#[derive(Clone, Debug, PartialEq)]
pub struct TriangleMesh {
    pub vertices: Vec<[f64; 3]>,
    pub triangles: Vec<[u32; 3]>,
}

impl TriangleMesh {
    /// The mesh of a file's bytes in `format`; `Err` with the reason where they are not a
    /// mesh of that format, hold no triangle, or have a coordinate that is not a finite number.
    /// Vertices at the same place are merged (STL repeats each corner in every triangle).
    ///
    /// ```
    /// use generator::model::{MeshFormat, TriangleMesh};
    /// let text = b"solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\nendfacet\nendsolid t\n";
    /// let mesh = TriangleMesh::from_bytes(text, MeshFormat::Stl).unwrap();
    /// assert_eq!((mesh.vertices.len(), mesh.triangles), (3, vec![[0, 1, 2]]));
    /// let obj = TriangleMesh::from_bytes(b"v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\nf 1 2 4\n", MeshFormat::Obj).unwrap();
    /// assert_eq!((obj.vertices.len(), obj.triangles.len()), (4, 2));
    /// ```
    pub fn from_bytes(bytes: &[u8], format: MeshFormat) -> Result<TriangleMesh, String> {
        let not = |e: &dyn std::fmt::Display| format!("it is not {} file ({e})", format.name());
        match format {
            MeshFormat::Stl => Self::merged(mesh_loader::stl::from_slice(bytes).map_err(|e| not(&e))?.meshes.iter().map(|m| (m, IDENTITY))),
            MeshFormat::Collada => collada(bytes).map_err(|e| not(&e)),
            // An OBJ file's materials (`mtllib`) are not read: the page draws every body in its
            // own colour.
            MeshFormat::Obj => {
                let scene =
                    mesh_loader::obj::from_slice(bytes, None, |_| Err::<Vec<u8>, _>(std::io::Error::other("materials are not read"))).map_err(|e| not(&e))?;
                Self::merged(scene.meshes.iter().map(|m| (m, IDENTITY)))
            }
        }
    }

    /// One mesh of `parts`, each placed by its transform (a 4 x 4 matrix acting on columns),
    /// vertices at the same place merged.
    fn merged<'a>(parts: impl Iterator<Item = (&'a mesh_loader::Mesh, Affine)>) -> Result<TriangleMesh, String> {
        let mut vertices: Vec<[f64; 3]> = Vec::new();
        let mut index: std::collections::HashMap<[u64; 3], u32> = std::collections::HashMap::new();
        let mut triangles = Vec::new();
        for (mesh, m) in parts {
            let mut at = Vec::with_capacity(mesh.vertices.len());
            for v in &mesh.vertices {
                if v.iter().any(|x| !x.is_finite()) {
                    return Err("a vertex has a coordinate that is not a finite number".into());
                }
                let v = v.map(f64::from);
                let p: [f64; 3] = std::array::from_fn(|i| m[i][0] * v[0] + m[i][1] * v[1] + m[i][2] * v[2] + m[i][3]);
                // `+ 0.0` makes -0 and 0 one key.
                let next = vertices.len() as u32;
                let k = *index.entry(p.map(|x| (x + 0.0).to_bits())).or_insert(next);
                if k == next {
                    vertices.push(p);
                }
                at.push(k);
            }
            for f in &mesh.faces {
                match f.map(|i| at.get(i as usize).copied()) {
                    [Some(a), Some(b), Some(c)] => triangles.push([a, b, c]),
                    _ => return Err("a face names a vertex the file does not have".into()),
                }
            }
        }
        if triangles.is_empty() {
            return Err("it holds no triangle".into());
        }
        if vertices.iter().flatten().any(|x| !x.is_finite()) {
            return Err("a vertex has a coordinate that is not a finite number".into());
        }
        Ok(TriangleMesh { vertices, triangles })
    }

    /// The lowest and highest corners of the box that bounds the vertices.
    ///
    /// ```
    /// use generator::model::TriangleMesh;
    /// let m = TriangleMesh { vertices: vec![[0.0, -1.0, 2.0], [3.0, 1.0, 0.0]], triangles: vec![] };
    /// assert_eq!(m.bounds(), ([0.0, -1.0, 0.0], [3.0, 1.0, 2.0]));
    /// ```
    pub fn bounds(&self) -> ([f64; 3], [f64; 3]) {
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for v in &self.vertices {
            for i in 0..3 {
                lo[i] = lo[i].min(v[i]);
                hi[i] = hi[i].max(v[i]);
            }
        }
        (lo, hi)
    }

    /// The mesh with at most `max` triangles: vertices merged by clustering on a grid over the
    /// bounding box (each cell's vertices become their mean), coarser until few enough
    /// triangles remain; triangles that collapse or repeat go. The same mesh gives the same
    /// result on any machine. A mesh already small enough comes back as it is, its unused
    /// vertices dropped.
    ///
    /// Vertex clustering, written here: a drawn outline needs no more, and the crates that
    /// simplify by edge collapse (`meshopt`) build C++ into every user of the generator.
    ///
    /// ```
    /// use generator::model::TriangleMesh;
    /// // A fan of 1000 thin triangles around the origin.
    /// let n = 1000;
    /// let mut vertices = vec![[0.0, 0.0, 0.0]];
    /// vertices.extend((0..n).map(|k| { let a = k as f64 * std::f64::consts::TAU / n as f64; [a.cos(), a.sin(), 0.0] }));
    /// let triangles = (0..n).map(|k| [0, 1 + k as u32, 1 + ((k + 1) % n) as u32]).collect();
    /// let small = TriangleMesh { vertices, triangles }.simplified(100);
    /// assert!(small.triangles.len() <= 100 && small.triangles.len() >= 8);
    /// ```
    pub fn simplified(&self, max: usize) -> TriangleMesh {
        let used = self.clustered(None);
        if used.triangles.len() <= max {
            return used;
        }
        let (lo, hi) = self.bounds();
        let largest = (0..3).map(|i| hi[i] - lo[i]).fold(0.0f64, f64::max);
        // A surface's triangles go about as the square of the cells across it: each try aims
        // a little under the bound from the last count, and steps down by at least one cell.
        let mut cells = 96usize;
        loop {
            let mesh = self.clustered(Some((lo, largest / cells as f64)));
            let count = mesh.triangles.len();
            if count <= max || cells <= 1 {
                return mesh;
            }
            let aim = (cells as f64 * (0.95 * max as f64 / count as f64).sqrt()) as usize;
            cells = aim.clamp(1, cells - 1);
        }
    }

    /// The mesh with vertices merged by grid cell (`grid`: the lowest corner and the cell's
    /// side), or, without a grid, with only its unused vertices dropped; collapsed and repeated
    /// triangles dropped.
    fn clustered(&self, grid: Option<([f64; 3], f64)>) -> TriangleMesh {
        let cell_of = |v: &[f64; 3], k: usize| -> [i64; 3] {
            match grid {
                Some((lo, side)) if side > 0.0 => std::array::from_fn(|i| ((v[i] - lo[i]) / side).floor() as i64),
                _ => [k as i64, 0, 0],
            }
        };
        let mut cluster_of = vec![u32::MAX; self.vertices.len()];
        let mut index: std::collections::HashMap<[i64; 3], u32> = std::collections::HashMap::new();
        let mut sums: Vec<([f64; 3], f64)> = Vec::new();
        let mut triangles = Vec::new();
        let mut seen = std::collections::HashSet::new();
        for t in &self.triangles {
            let c = t.map(|v| {
                let v = v as usize;
                if cluster_of[v] == u32::MAX {
                    let next = sums.len() as u32;
                    let k = *index.entry(cell_of(&self.vertices[v], v)).or_insert(next);
                    if k == next {
                        sums.push(([0.0; 3], 0.0));
                    }
                    let (s, n) = &mut sums[k as usize];
                    for i in 0..3 {
                        s[i] += self.vertices[v][i];
                    }
                    *n += 1.0;
                    cluster_of[v] = k;
                }
                cluster_of[v]
            });
            if c[0] == c[1] || c[1] == c[2] || c[0] == c[2] {
                continue;
            }
            let mut key = c;
            key.sort_unstable();
            if seen.insert(key) {
                triangles.push(c);
            }
        }
        let vertices = sums.iter().map(|(s, n)| s.map(|x| x / n)).collect();
        TriangleMesh { vertices, triangles }
    }
}

/// A 4 x 4 transform acting on columns `[x, y, z, 1]`.
type Affine = [[f64; 4]; 4];

const IDENTITY: Affine = [[1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0], [0.0, 0.0, 0.0, 1.0]];

fn compose(a: &Affine, b: &Affine) -> Affine {
    std::array::from_fn(|i| std::array::from_fn(|j| (0..4).map(|k| a[i][k] * b[k][j]).sum()))
}

/// Deepest nesting of a COLLADA scene's nodes followed (a node instancing itself is a loop).
const MAX_COLLADA_DEPTH: usize = 64;

/// A COLLADA file's mesh: `mesh-loader` reads the geometries, and the scene that places them
/// is read here, each `<instance_geometry>` under its nodes' transforms composed parent first,
/// in metres by the `<unit>`. (`mesh-loader` 0.1.13 composes nested nodes child first and leaves
/// a node's translation out of the unit's scale: a node turning a child that moves drew the
/// part elsewhere, and a file in millimetres with a `<translate>` placed it a thousand times
/// too far.) Without a scene, every geometry once, as it is.
fn collada(bytes: &[u8]) -> Result<TriangleMesh, String> {
    let text = std::str::from_utf8(bytes).map_err(|e| format!("not UTF-8 text: {e}"))?;
    let doc = roxmltree::Document::parse(text).map_err(|e| e.to_string())?;
    let root = doc.root_element();
    if root.tag_name().name() != "COLLADA" {
        return Err("its root element is not <COLLADA>".into());
    }
    // The geometries alone: the scene's elements blanked (same length: `mesh-loader` places
    // nothing then, and reports its errors at the same places).
    let mut geometry_only = text.as_bytes().to_vec();
    for c in root.children().filter(|c| matches!(c.tag_name().name(), "library_visual_scenes" | "library_nodes" | "scene")) {
        geometry_only[c.range()].iter_mut().for_each(|b| *b = b' ');
    }
    let geometry_only = String::from_utf8(geometry_only).map_err(|e| e.to_string())?;
    let scene = mesh_loader::collada::from_str(&geometry_only).map_err(|e| e.to_string())?;
    let parts: std::collections::HashMap<&str, &mesh_loader::Mesh> = scene.meshes.iter().map(|m| (m.name.as_str(), m)).collect();
    let unit = element(root, "asset")
        .and_then(|a| element(a, "unit"))
        .and_then(|u| u.attribute("meter"))
        .map_or(Ok(1.0), |m| m.trim().parse::<f64>().map_err(|_| format!("its <unit meter=\"{m}\"> is not a number")))?;
    if !(unit > 0.0 && unit.is_finite()) {
        return Err(format!("its <unit> is {unit} metres"));
    }
    let scale = [[unit, 0.0, 0.0, 0.0], [0.0, unit, 0.0, 0.0], [0.0, 0.0, unit, 0.0], [0.0, 0.0, 0.0, 1.0]];
    // Elements by id, for `url="#id"`.
    let by_id: std::collections::HashMap<&str, roxmltree::Node<'_, '_>> = root.descendants().filter_map(|n| n.attribute("id").map(|id| (id, n))).collect();
    let target = |n: roxmltree::Node<'_, '_>| n.attribute("url").and_then(|u| u.strip_prefix('#')).and_then(|id| by_id.get(id).copied());
    let visual_scene = element(root, "scene")
        .and_then(|s| element(s, "instance_visual_scene"))
        .and_then(target)
        .or_else(|| element(root, "library_visual_scenes").and_then(|l| element(l, "visual_scene")));
    let mut placed: Vec<(&mesh_loader::Mesh, Affine)> = Vec::new();
    match visual_scene {
        Some(vs) => {
            for n in vs.children().filter(|c| c.tag_name().name() == "node") {
                place_node(n, &scale, 0, &target, &parts, &mut placed)?;
            }
        }
        None => placed.extend(scene.meshes.iter().map(|m| (m, scale))),
    }
    TriangleMesh::merged(placed.into_iter())
}

/// The first child element of `n` named `name`.
fn element<'a, 'input>(n: roxmltree::Node<'a, 'input>, name: &str) -> Option<roxmltree::Node<'a, 'input>> {
    n.children().find(|c| c.is_element() && c.tag_name().name() == name)
}

/// Adds the geometries `node` instances (and its children's, and the nodes it instances) to
/// `placed`, under `parent` and the node's own transforms in document order.
fn place_node<'a, 'input>(
    node: roxmltree::Node<'a, 'input>,
    parent: &Affine,
    depth: usize,
    target: &dyn Fn(roxmltree::Node<'a, 'input>) -> Option<roxmltree::Node<'a, 'input>>,
    parts: &std::collections::HashMap<&str, &'a mesh_loader::Mesh>,
    placed: &mut Vec<(&'a mesh_loader::Mesh, Affine)>,
) -> Result<(), String> {
    if depth > MAX_COLLADA_DEPTH {
        return Err(format!("its nodes nest deeper than {MAX_COLLADA_DEPTH} (a node that instances itself?)"));
    }
    let mut m = *parent;
    for c in node.children().filter(|c| c.is_element()) {
        let name = c.tag_name().name();
        if !matches!(name, "matrix" | "translate" | "rotate" | "scale" | "lookat" | "skew") {
            continue;
        }
        let numbers: Vec<f64> = c
            .text()
            .unwrap_or("")
            .split_whitespace()
            .map(str::parse)
            .collect::<Result<_, _>>()
            .map_err(|_| format!("a <{name}> holds something other than numbers"))?;
        let want = match name {
            "matrix" => 16,
            "translate" | "scale" => 3,
            "rotate" => 4,
            _ => return Err(format!("a node is placed by <{name}>, which is not read: export it with matrices")),
        };
        if numbers.len() != want {
            return Err(format!("a <{name}> holds {} numbers, not {want}", numbers.len()));
        }
        let t: Affine = match name {
            "matrix" => std::array::from_fn(|i| std::array::from_fn(|j| numbers[4 * i + j])),
            "translate" => [[1.0, 0.0, 0.0, numbers[0]], [0.0, 1.0, 0.0, numbers[1]], [0.0, 0.0, 1.0, numbers[2]], [0.0, 0.0, 0.0, 1.0]],
            "scale" => [[numbers[0], 0.0, 0.0, 0.0], [0.0, numbers[1], 0.0, 0.0], [0.0, 0.0, numbers[2], 0.0], [0.0, 0.0, 0.0, 1.0]],
            _ => {
                // Rodrigues' formula about the unit axis, the angle in degrees.
                let norm = (numbers[0] * numbers[0] + numbers[1] * numbers[1] + numbers[2] * numbers[2]).sqrt();
                if norm == 0.0 {
                    continue;
                }
                let [x, y, z] = [numbers[0] / norm, numbers[1] / norm, numbers[2] / norm];
                let (s, c) = numbers[3].to_radians().sin_cos();
                let v = 1.0 - c;
                [
                    [c + x * x * v, x * y * v - z * s, x * z * v + y * s, 0.0],
                    [y * x * v + z * s, c + y * y * v, y * z * v - x * s, 0.0],
                    [z * x * v - y * s, z * y * v + x * s, c + z * z * v, 0.0],
                    [0.0, 0.0, 0.0, 1.0],
                ]
            }
        };
        m = compose(&m, &t);
    }
    for c in node.children().filter(|c| c.is_element()) {
        match c.tag_name().name() {
            "instance_geometry" => {
                let id = c.attribute("url").and_then(|u| u.strip_prefix('#')).unwrap_or("");
                let part = parts.get(id).ok_or_else(|| format!("a node instances geometry `{id}`, which the file does not hold"))?;
                placed.push((part, m));
            }
            "node" => place_node(c, &m, depth + 1, target, parts, placed)?,
            "instance_node" => {
                let n = target(c).ok_or_else(|| format!("a node instances node `{}`, which the file does not hold", c.attribute("url").unwrap_or("")))?;
                place_node(n, &m, depth + 1, target, parts, placed)?;
            }
            _ => {}
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Meshes read are kept, the last KEPT_MESHES of them: the same file unchanged comes back
    /// without being read again (the same mesh), and reading more files than that keeps no more.
    #[test]
    fn the_meshes_read_are_kept_and_bounded() {
        let dir = tempfile::tempdir().unwrap();
        let triangle =
            |k: usize| format!("solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex {} 0 0\nvertex 0 1 0\nendloop\nendfacet\nendsolid t\n", k + 1);
        let paths: Vec<_> = (0..KEPT_MESHES + 20).map(|k| dir.path().join(format!("m{k}.stl"))).collect();
        for (k, path) in paths.iter().enumerate() {
            std::fs::write(path, triangle(k)).unwrap();
            let first = drawn_mesh(path).unwrap();
            assert_eq!(first.vertices[1][0], (k + 1) as f64);
            assert!(std::sync::Arc::ptr_eq(&first, &drawn_mesh(path).unwrap()), "{k}: read again");
            assert!(READ.lock().unwrap().len() <= KEPT_MESHES);
        }
        // The first files read have made way for the last.
        let kept = |path: &std::path::PathBuf| READ.lock().unwrap().iter().any(|(p, _, _)| *p == std::fs::canonicalize(path).unwrap());
        assert!(!kept(&paths[0]) && kept(&paths[paths.len() - 1]));
    }

    /// A closed box of 12 triangles as binary STL, its 80-byte header `header`.
    fn binary_cube(header: &[u8]) -> Vec<u8> {
        let c = |i: usize| [(i & 1) as f32, ((i >> 1) & 1) as f32, ((i >> 2) & 1) as f32];
        let faces = [[0, 2, 3], [0, 3, 1], [4, 5, 7], [4, 7, 6], [0, 1, 5], [0, 5, 4], [2, 6, 7], [2, 7, 3], [0, 4, 6], [0, 6, 2], [1, 3, 7], [1, 7, 5]];
        let mut out = vec![b' '; 80];
        out[..header.len()].copy_from_slice(header);
        out.extend((faces.len() as u32).to_le_bytes());
        for f in faces {
            out.extend([0f32; 3].iter().flat_map(|x| x.to_le_bytes()));
            for v in f {
                out.extend(c(v).iter().flat_map(|x| x.to_le_bytes()));
            }
            out.extend([0u8; 2]);
        }
        out
    }

    /// Binary STL is read whatever its header says, "solid" included (a common exporter habit
    /// that the text reader would otherwise take for its own): eight corners, twelve triangles.
    #[test]
    fn binary_stl_is_read_even_when_its_header_says_solid() {
        for header in [&b"made by hand"[..], b"solid cube, exported"] {
            let mesh = TriangleMesh::from_bytes(&binary_cube(header), MeshFormat::Stl).unwrap();
            assert_eq!((mesh.vertices.len(), mesh.triangles.len()), (8, 12), "{:?}", String::from_utf8_lossy(header));
            assert_eq!(mesh.bounds(), ([0.0; 3], [1.0; 3]));
        }
    }

    /// A COLLADA document whose unit is `meter` metres: one triangle and one quad (two
    /// triangles) of side 1000 units at the origin, `Y_UP`, placed by the scene's `nodes`.
    fn collada(meter: &str, nodes: &str) -> String {
        format!(
            r##"<?xml version="1.0" encoding="utf-8"?>
<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">
  <asset><unit name="u" meter="{meter}"/><up_axis>Y_UP</up_axis></asset>
  <library_geometries>
    <geometry id="part" name="part"><mesh>
      <source id="part-pos">
        <float_array id="part-pos-array" count="15">0 0 0 1000 0 0 0 1000 0 0 0 1000 1000 0 1000</float_array>
        <technique_common><accessor source="#part-pos-array" count="5" stride="3">
          <param name="X" type="float"/><param name="Y" type="float"/><param name="Z" type="float"/>
        </accessor></technique_common>
      </source>
      <vertices id="part-vtx"><input semantic="POSITION" source="#part-pos"/></vertices>
      <triangles count="1"><input semantic="VERTEX" source="#part-vtx" offset="0"/><p>0 1 2</p></triangles>
      <polylist count="1"><input semantic="VERTEX" source="#part-vtx" offset="0"/><vcount>4</vcount><p>0 1 4 3</p></polylist>
    </mesh></geometry>
  </library_geometries>
  <library_nodes><node id="lib"><translate>0 2000 0</translate><instance_geometry url="#part"/></node></library_nodes>
  <library_visual_scenes><visual_scene id="scene">{nodes}</visual_scene></library_visual_scenes>
  <scene><instance_visual_scene url="#scene"/></scene>
</COLLADA>"##
        )
    }

    /// A COLLADA file's unit scales it, translations included, and its nodes place it, parent
    /// first; its `Y_UP` is not applied (as in RViz): the quad stays in the plane y = 0.
    #[test]
    fn collada_is_read_in_metres_where_its_nodes_place_it() {
        let read = |meter: &str, nodes: &str| TriangleMesh::from_bytes(collada(meter, nodes).as_bytes(), MeshFormat::Collada).unwrap();
        let near = |a: [f64; 3], b: [f64; 3]| a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-6);
        let has = |m: &TriangleMesh, p: [f64; 3]| m.vertices.iter().any(|v| near(*v, p));
        // Millimetres, moved up by 500 of them.
        let mm = read("0.001", r##"<node id="n"><translate>0 0 500</translate><instance_geometry url="#part"/></node>"##);
        assert_eq!((mm.vertices.len(), mm.triangles.len()), (5, 3));
        let (lo, hi) = mm.bounds();
        assert!(near(lo, [0.0, 0.0, 0.5]) && near(hi, [1.0, 1.0, 1.5]), "{lo:?} {hi:?}");
        assert!(has(&mm, [1.0, 0.0, 1.5]), "{:?}", mm.vertices);
        // A parent turning a quarter about z and a child moving 1 along x: the child's corner
        // lands at (0, 1, 0), turned with it.
        let nested =
            read("1", r##"<node id="p"><rotate>0 0 1 90</rotate><node id="c"><translate>1 0 0</translate><instance_geometry url="#part"/></node></node>"##);
        assert!(has(&nested, [0.0, 1.0, 0.0]) && has(&nested, [0.0, 1001.0, 0.0]) && has(&nested, [-1000.0, 1.0, 0.0]), "{:?}", nested.vertices);
        // One node: the translation after the turn, in document order.
        let one = read("1", r##"<node id="n"><translate>1 0 0</translate><rotate>0 0 1 90</rotate><instance_geometry url="#part"/></node>"##);
        assert!(has(&one, [1.0, 0.0, 0.0]) && has(&one, [1.0, 1000.0, 0.0]), "{:?}", one.vertices);
        // A node of the library, instanced twice: two copies, 2 m apart in y.
        let twice = read(
            "0.001",
            r##"<node id="a"><instance_node url="#lib"/></node><node id="b"><translate>0 -2000 0</translate><instance_node url="#lib"/></node>"##,
        );
        assert_eq!(twice.triangles.len(), 6);
        assert!(has(&twice, [0.0, 2.0, 0.0]) && has(&twice, [0.0, 0.0, 0.0]), "{:?}", twice.vertices);
        // What cannot be placed is refused, saying why.
        let refused = |nodes: &str| TriangleMesh::from_bytes(collada("1", nodes).as_bytes(), MeshFormat::Collada).unwrap_err();
        assert!(refused(r##"<node id="n"><instance_geometry url="#gone"/></node>"##).contains("`gone`"));
        assert!(refused(r##"<node id="n"><lookat>0 0 1 0 0 0 0 1 0</lookat><instance_geometry url="#part"/></node>"##).contains("<lookat>"));
        assert!(refused(r##"<node id="n"><instance_node url="#n"/></node>"##).contains("deeper"));
        assert!(refused(r##"<node id="n"><translate>0 1</translate><instance_geometry url="#part"/></node>"##).contains("2 numbers"));
    }

    /// Bytes that are no STL, an empty mesh and a NaN coordinate are refused, saying why.
    #[test]
    fn what_is_not_a_mesh_is_refused() {
        assert!(TriangleMesh::from_bytes(b"<?xml version=\"1.0\"?><COLLADA/>", MeshFormat::Stl).unwrap_err().contains("not an STL"));
        assert!(TriangleMesh::from_bytes(b"solid empty\nendsolid empty\n", MeshFormat::Stl).unwrap_err().contains("no triangle"));
        assert!(TriangleMesh::from_bytes(b"solid t\n", MeshFormat::Collada).unwrap_err().contains("not a COLLADA"));
        assert!(TriangleMesh::from_bytes(b"v 0 0 0\nv 1 0 0\nf 1 2 7\n", MeshFormat::Obj).is_err());
        assert!(TriangleMesh::from_bytes(b"v 0 0 0\n", MeshFormat::Obj).unwrap_err().contains("no triangle"));
        let mut nan = binary_cube(b"cube");
        nan[84 + 12..84 + 16].copy_from_slice(&f32::NAN.to_le_bytes());
        assert!(TriangleMesh::from_bytes(&nan, MeshFormat::Stl).unwrap_err().contains("finite"));
    }

    /// A fine sphere simplifies under the bound, stays a closed outline of about its size, and
    /// simplifies to the same bytes twice; a small mesh is kept as it is.
    #[test]
    fn simplification_keeps_the_outline_under_the_bound() {
        let (bands, sides) = (60, 120);
        let at = |j: usize, k: usize| {
            let (a, b) = (std::f64::consts::PI * j as f64 / bands as f64, std::f64::consts::TAU * k as f64 / sides as f64);
            [a.sin() * b.cos(), a.sin() * b.sin(), a.cos()]
        };
        let mut vertices = Vec::new();
        let mut triangles = Vec::new();
        for j in 0..=bands {
            for k in 0..sides {
                vertices.push(at(j, k));
            }
        }
        let id = |j: usize, k: usize| (j * sides + k % sides) as u32;
        for j in 0..bands {
            for k in 0..sides {
                triangles.push([id(j, k), id(j + 1, k), id(j + 1, k + 1)]);
                triangles.push([id(j, k), id(j + 1, k + 1), id(j, k + 1)]);
            }
        }
        let fine = TriangleMesh { vertices, triangles };
        let small = fine.simplified(MAX_DRAWN_TRIANGLES);
        assert!(small.triangles.len() <= MAX_DRAWN_TRIANGLES && small.triangles.len() > MAX_DRAWN_TRIANGLES / 4, "{}", small.triangles.len());
        let (lo, hi) = small.bounds();
        assert!(lo.iter().chain(&hi).all(|x| (x.abs() - 1.0).abs() < 0.1), "{lo:?} {hi:?}");
        assert!(small.vertices.iter().all(|v| (v.iter().map(|x| x * x).sum::<f64>().sqrt() - 1.0).abs() < 0.15));
        assert_eq!(small, fine.simplified(MAX_DRAWN_TRIANGLES));
        let cube = TriangleMesh::from_bytes(&binary_cube(b"cube"), MeshFormat::Stl).unwrap();
        assert_eq!(cube.simplified(MAX_DRAWN_TRIANGLES), cube);
    }
}
