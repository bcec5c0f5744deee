//! Tangent frames for normal mapping.
//!
//! Normal maps are baked against MikkTSpace tangents, so meshes with UVs but no tangents get them
//! from the `mikktspace` crate. Whatever the source (file, MikkTSpace or none), [`orthonormalize`]
//! then makes every tangent unit length and orthogonal to its normal, so shaders never see NaN or a
//! zero vector.

use std::collections::HashMap;

use glam::{Vec3, Vec4};

use super::Vertex;

/// Computes MikkTSpace tangents for an indexed triangle list along texture coordinates `uv_set`
/// ([`Vertex::uv`]), then orthonormalizes them.
///
/// MikkTSpace works per triangle corner. Where corners sharing a vertex get different tangents (UV
/// seams, mirrored UVs), the vertex is split so that each copy keeps its own; `indices` are updated.
/// Returns the vertex each vertex now is a copy of (itself for those that were there), for what
/// else is stored per vertex (skin weights, morph targets). Normals must be unit length.
pub(crate) fn generate(vertices: &mut Vec<Vertex>, indices: &mut [u32], uv_set: u32) -> Vec<u32> {
    let mut sources: Vec<u32> = (0..vertices.len() as u32).collect();
    // The mikktspace crate panics where every corner lies at one point; a mesh without a triangle of
    // any area has no tangent frame to find anyway.
    let position = |i: u32| Vec3::from(vertices[i as usize].position);
    let has_area = indices.chunks_exact(3).any(|t| (position(t[1]) - position(t[0])).cross(position(t[2]) - position(t[0])) != Vec3::ZERO);
    let mut corners = Corners { vertices, indices, uv_set, tangents: vec![[0.0; 4]; indices.len()] };
    // On failure (no usable triangles) the tangents stay zero and orthonormalize() substitutes
    // arbitrary ones, which is all a mesh without a usable UV layout can have.
    if has_area && mikktspace::generate_tangents(&mut corners) {
        let tangents = corners.tangents;
        weld(vertices, indices, &tangents, &mut sources);
    }
    orthonormalize(vertices);
    sources
}

/// Makes each tangent orthogonal to its normal and unit length, keeping the sign in w (±1). Where
/// that is impossible (zero, NaN, or parallel to the normal) any perpendicular unit tangent with
/// w = 1 is used instead. Normals must be unit length.
pub(crate) fn orthonormalize(vertices: &mut [Vertex]) {
    for v in vertices {
        let normal = Vec3::from(v.normal);
        let tangent = Vec4::from(v.tangent);
        let sign = if tangent.w < 0.0 { -1.0 } else { 1.0 };
        let projected = tangent.truncate() - normal * normal.dot(tangent.truncate());
        // Below this length the projection is dominated by rounding error.
        let usable = projected.is_finite() && projected.length() > 1e-3 * tangent.truncate().length();
        v.tangent = match projected.try_normalize() {
            Some(t) if usable => t.extend(sign),
            _ => normal.any_orthonormal_vector().extend(1.0),
        }
        .to_array();
    }
}

/// Writes per-corner tangents back to the shared vertices, splitting vertices whose corners disagree.
fn weld(vertices: &mut Vec<Vertex>, indices: &mut [u32], tangents: &[[f32; 4]], sources: &mut Vec<u32>) {
    let mut assigned = vec![false; vertices.len()];
    let mut splits: HashMap<(u32, [u32; 4]), u32> = HashMap::new();
    for (index, &tangent) in indices.iter_mut().zip(tangents) {
        let v = *index as usize;
        if !assigned[v] {
            assigned[v] = true;
            vertices[v].tangent = tangent;
        } else if vertices[v].tangent.map(f32::to_bits) != tangent.map(f32::to_bits) {
            *index = *splits.entry((*index, tangent.map(f32::to_bits))).or_insert_with(|| {
                let copy = Vertex { tangent, ..vertices[v] };
                vertices.push(copy);
                sources.push(v as u32);
                (vertices.len() - 1) as u32
            });
        }
    }
}

/// The mesh as MikkTSpace sees it: triangles of corners, one tangent written per corner.
struct Corners<'a> {
    vertices: &'a [Vertex],
    indices: &'a [u32],
    uv_set: u32,
    tangents: Vec<[f32; 4]>,
}

impl Corners<'_> {
    fn vertex(&self, face: usize, vert: usize) -> &Vertex {
        &self.vertices[self.indices[face * 3 + vert] as usize]
    }
}

impl mikktspace::Geometry for Corners<'_> {
    fn num_faces(&self) -> usize {
        self.indices.len() / 3
    }

    fn num_vertices_of_face(&self, _face: usize) -> usize {
        3
    }

    fn position(&self, face: usize, vert: usize) -> [f32; 3] {
        self.vertex(face, vert).position
    }

    fn normal(&self, face: usize, vert: usize) -> [f32; 3] {
        self.vertex(face, vert).normal
    }

    fn tex_coord(&self, face: usize, vert: usize) -> [f32; 2] {
        // glTF's v runs down the image while normal maps store +Y (green) up the image, the
        // convention tangents in glTF files follow (w = +1 for an unmirrored layout). MikkTSpace takes
        // the bitangent sign from the direction of increasing v, so it is given v flipped.
        let [u, v] = self.vertex(face, vert).uv(self.uv_set);
        [u, -v]
    }

    fn set_tangent_encoded(&mut self, tangent: [f32; 4], face: usize, vert: usize) {
        self.tangents[face * 3 + vert] = tangent;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn vertex(position: [f32; 3], uv: [f32; 2]) -> Vertex {
        Vertex { position, u: uv[0], normal: [0.0, 0.0, 1.0], v: uv[1], ..Vertex::default() }
    }

    /// A quad facing +Z with the image upright on it (u right, v down), counter-clockwise.
    fn upright_quad() -> (Vec<Vertex>, Vec<u32>) {
        let vertices = vec![
            vertex([-1.0, -1.0, 0.0], [0.0, 1.0]),
            vertex([1.0, -1.0, 0.0], [1.0, 1.0]),
            vertex([1.0, 1.0, 0.0], [1.0, 0.0]),
            vertex([-1.0, 1.0, 0.0], [0.0, 0.0]),
        ];
        (vertices, vec![0, 1, 2, 0, 2, 3])
    }

    #[test]
    fn upright_image_gets_tangent_along_u_and_bitangent_up_the_image() {
        let (mut vertices, mut indices) = upright_quad();
        generate(&mut vertices, &mut indices, 0);
        assert_eq!(vertices.len(), 4, "no seam, no split");
        for v in &vertices {
            let t = Vec4::from(v.tangent);
            assert!(t.truncate().abs_diff_eq(Vec3::X, 1e-5), "{t}");
            // bitangent = cross(normal, tangent) * w = +Y: up the image, as glTF normal maps expect.
            assert_eq!(t.w, 1.0);
        }
    }

    #[test]
    fn tangents_follow_the_set_of_coordinates_asked_for() {
        // The second set turns the image a quarter: its u runs up the quad (+Y), its v along +X.
        let (mut vertices, mut indices) = upright_quad();
        for v in &mut vertices {
            v.uv1 = [(v.position[1] + 1.0) / 2.0, (v.position[0] + 1.0) / 2.0];
        }
        generate(&mut vertices, &mut indices, 1);
        for v in &vertices {
            let t = Vec4::from(v.tangent);
            assert!(t.truncate().abs_diff_eq(Vec3::Y, 1e-5), "{t}");
            // v runs down the image along +X, so the bitangent (up the image) is −X = cross(Z, Y) × 1.
            assert_eq!(t.w, 1.0);
        }
    }

    #[test]
    fn mirrored_half_splits_shared_vertices() {
        // Two quads sharing an edge; the right one has its image mirrored horizontally.
        let (mut vertices, mut indices) = upright_quad();
        vertices.push(vertex([3.0, -1.0, 0.0], [0.0, 1.0]));
        vertices.push(vertex([3.0, 1.0, 0.0], [0.0, 0.0]));
        indices.extend([1, 4, 5, 1, 5, 2]);
        generate(&mut vertices, &mut indices, 0);
        assert!(vertices.len() > 6, "the shared edge's vertices are split");
        let signs: Vec<f32> = indices.iter().map(|&i| vertices[i as usize].tangent[3]).collect();
        assert!(signs[..6].iter().all(|&w| w == 1.0), "{signs:?}");
        assert!(signs[6..].iter().all(|&w| w == -1.0), "{signs:?}");
    }

    /// Triangles without area (here every index 0, as a glTF accessor without data gives) get the
    /// fallback tangents, never MikkTSpace's panic.
    #[test]
    fn meshes_without_area_get_fallback_tangents() {
        let (mut vertices, _) = upright_quad();
        let mut indices = vec![0; 6];
        generate(&mut vertices, &mut indices, 0);
        assert!(vertices.iter().all(|v| Vec4::from(v.tangent).truncate().length() > 0.99), "{vertices:?}");
    }

    #[test]
    fn degenerate_tangents_get_a_perpendicular_fallback() {
        let mut vertices = vec![
            Vertex { tangent: [f32::NAN, 0.0, 0.0, 1.0], ..vertex([0.0; 3], [0.0; 2]) },
            Vertex { tangent: [0.0, 0.0, 2.0, -1.0], ..vertex([0.0; 3], [0.0; 2]) },
            Vertex { tangent: [3.0, 0.0, 1.0, -1.0], ..vertex([0.0; 3], [0.0; 2]) },
        ];
        orthonormalize(&mut vertices);
        for v in &vertices {
            let t = Vec4::from(v.tangent);
            assert!((t.truncate().length() - 1.0).abs() < 1e-5 && t.z.abs() < 1e-5, "{t}");
        }
        assert_eq!(vertices[1].tangent[3], 1.0, "fallback tangents have w = 1");
        assert_eq!(vertices[2].tangent, [1.0, 0.0, 0.0, -1.0], "usable tangents keep their sign");
    }
}
