//! A solid given as a triangle mesh: read from an STL file (binary or text, by the `stl_io`
//! crate) and simplified to at most a few hundred triangles for drawing, deterministically.

/// The most triangles a mesh keeps when read ([`TriangleMesh::simplified`]): the page sorts and
/// fills every face at every frame (and shares a total among a model's meshes, the animation's
/// own bound), so a finer mesh would only cost memory and reading time.
pub const MAX_DRAWN_TRIANGLES: usize = 400;

/// The most bytes a mesh file may hold (64 MiB: a scanned part of a million triangles).
pub const MAX_MESH_BYTES: u64 = 64 << 20;

/// Why a mesh file could not be drawn.
#[derive(Debug)]
pub enum MeshError {
    /// It could not be read, or holds more than [`MAX_MESH_BYTES`].
    Read(files::FileError),
    /// It is not an STL mesh ([`TriangleMesh::from_stl`]'s reason).
    Format(String),
}

/// The mesh of the STL file at `path`, simplified for drawing ([`MAX_DRAWN_TRIANGLES`]).
/// A file is read once per process while its size and modification time stay the same: a URDF
/// is checked, then built, and `watch` rebuilds a model on every save, and a robot's meshes can
/// be tens of megabytes.
pub fn drawn_mesh(path: &std::path::Path) -> Result<std::sync::Arc<TriangleMesh>, MeshError> {
    type Stamp = (u64, Option<std::time::SystemTime>);
    static READ: std::sync::Mutex<Vec<(std::path::PathBuf, Stamp, std::sync::Arc<TriangleMesh>)>> = std::sync::Mutex::new(Vec::new());
    // Keyed by the canonical path: a URDF names a file through `..` one way, the model another.
    let path = &std::fs::canonicalize(path).unwrap_or_else(|_| path.to_path_buf());
    let stamp: Option<Stamp> = std::fs::metadata(path).ok().map(|m| (m.len(), m.modified().ok()));
    // A poisoned lock only means another thread panicked while holding it; the list stays valid.
    let mut read = READ.lock().unwrap_or_else(|e| e.into_inner());
    if let Some((_, _, mesh)) = read.iter().find(|(p, s, _)| p == path && stamp.as_ref() == Some(s)) {
        return Ok(mesh.clone());
    }
    drop(read);
    let bytes = files::read_bounded(path, MAX_MESH_BYTES).map_err(MeshError::Read)?;
    let mesh = std::sync::Arc::new(TriangleMesh::from_stl(&bytes).map_err(MeshError::Format)?.simplified(MAX_DRAWN_TRIANGLES));
    if let Some(stamp) = stamp {
        read = READ.lock().unwrap_or_else(|e| e.into_inner());
        read.retain(|(p, _, _)| p != path);
        read.push((path.to_path_buf(), stamp, mesh.clone()));
    }
    Ok(mesh)
}

/// A triangle mesh in its file's own units and axes: vertices, and triangles as indices into
/// them, counter-clockwise seen from outside (STL's rule; the page lights both sides, so a file
/// that breaks the rule still draws).
#[derive(Clone, Debug, PartialEq)]
pub struct TriangleMesh {
    pub vertices: Vec<[f64; 3]>,
    pub triangles: Vec<[u32; 3]>,
}

impl TriangleMesh {
    /// The mesh of an STL file's bytes, binary or text; `Err` with the reason where it is
    /// neither, holds no triangle, or has a coordinate that is not a finite number.
    ///
    /// ```
    /// use generator::model::mesh::TriangleMesh;
    /// let text = b"solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\nendfacet\nendsolid t\n";
    /// let mesh = TriangleMesh::from_stl(text).unwrap();
    /// assert_eq!((mesh.vertices.len(), mesh.triangles), (3, vec![[0, 1, 2]]));
    /// ```
    pub fn from_stl(bytes: &[u8]) -> Result<TriangleMesh, String> {
        // A binary STL's 80-byte header is free text, and many exporters begin it with "solid",
        // which `stl_io` takes for the text format: a file whose length is exactly that of a
        // binary STL of the count it states is read as binary, its header blanked.
        let binary = bytes.get(80..84).map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]) as usize).is_some_and(|n| bytes.len() == 84 + 50 * n);
        let mut owned;
        let bytes = if binary && bytes.starts_with(b"solid") {
            owned = bytes.to_vec();
            owned[..5].copy_from_slice(b"     ");
            &owned[..]
        } else {
            bytes
        };
        let mesh = stl_io::read_stl(&mut std::io::Cursor::new(bytes)).map_err(|e| format!("it is not an STL file ({e})"))?;
        if mesh.faces.is_empty() {
            return Err("it holds no triangle".into());
        }
        let vertices: Vec<[f64; 3]> = mesh.vertices.iter().map(|v| v.0.map(f64::from)).collect();
        if vertices.iter().flatten().any(|x| !x.is_finite()) {
            return Err("a vertex has a coordinate that is not a finite number".into());
        }
        let triangles = mesh.faces.iter().map(|f| f.vertices.map(|i| i as u32)).collect();
        Ok(TriangleMesh { vertices, triangles })
    }

    /// The lowest and highest corners of the box that bounds the vertices.
    ///
    /// ```
    /// use generator::model::mesh::TriangleMesh;
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
    /// use generator::model::mesh::TriangleMesh;
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

#[cfg(test)]
mod tests {
    use super::*;

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
            let mesh = TriangleMesh::from_stl(&binary_cube(header)).unwrap();
            assert_eq!((mesh.vertices.len(), mesh.triangles.len()), (8, 12), "{:?}", String::from_utf8_lossy(header));
            assert_eq!(mesh.bounds(), ([0.0; 3], [1.0; 3]));
        }
    }

    /// Bytes that are no STL, an empty mesh and a NaN coordinate are refused, saying why.
    #[test]
    fn what_is_not_a_mesh_is_refused() {
        assert!(TriangleMesh::from_stl(b"<?xml version=\"1.0\"?><COLLADA/>").unwrap_err().contains("not an STL"));
        assert!(TriangleMesh::from_stl(b"solid empty\nendsolid empty\n").unwrap_err().contains("no triangle"));
        let mut nan = binary_cube(b"cube");
        nan[84 + 12..84 + 16].copy_from_slice(&f32::NAN.to_le_bytes());
        assert!(TriangleMesh::from_stl(&nan).unwrap_err().contains("finite"));
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
        let cube = TriangleMesh::from_stl(&binary_cube(b"cube")).unwrap();
        assert_eq!(cube.simplified(MAX_DRAWN_TRIANGLES), cube);
    }
}
