//! Ray tracing against the scene's triangles, for the hybrid passes (PowerVR's "rays from the
//! G-buffer"): sun shadows (`passes/ray_shadows.rs`) and reflections shaded by the shading core at
//! their hit points (`shading/reflections.wgsl`).
//!
//! No GPU here has ray queries, so the hierarchy is our own, in the node layout of the volume
//! structures (`accel/bvh.rs`): a bottom level (BLAS) per mesh over its triangles in mesh space,
//! built once on the CPU with the binned SAH builder, and a top level (TLAS) over the scene's mesh
//! instances, one instance per leaf, each with the inverse of its affine transform, so a mesh placed
//! many times is stored once. `trace.wgsl` walks both levels without a stack, as the point query does
//! (`entry` into a node whose box the ray meets, `skip` past it otherwise), for the closest hit or any
//! hit; alpha-masked triangles are tested against their material's alpha at the hit.
//!
//! Triangles are stored in leaf order with one vertex and two edges (Möller–Trumbore needs nothing
//! else), so a leaf's triangles are one contiguous read; leaves and top-level leaves name their
//! triangles and instances directly, without an index array. Primitives drawn over the opaque
//! image (alpha-blended or transmissive, `Material::drawn_over_opaque`) are left out: rays see
//! opaque and alpha-masked surfaces.

pub mod hardware;
pub mod refit;

use glam::{Affine3A, Vec3};

use crate::{
    accel::{Bvh, BvhNode},
    gpu::scene::{RayBuffers, Records},
    scene::{Aabb, AlphaMode, Scene},
    Error, Result,
};

/// Set in `RayTriangle::draw_offset` when the triangle's material is alpha-masked: a candidate hit
/// is kept only where the material's alpha reaches its cutoff.
pub const ALPHA_MASKED: u32 = 1 << 31;

/// Most triangles a leaf of a BLAS holds: rays test a leaf's triangles one after the other.
const BLAS_LEAF_SIZE: u32 = 4;

/// One triangle as rays test it, in its mesh's space. Keep in sync with `RayTriangle` in
/// `rays/ray_types.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct RayTriangle {
    pub v0: [f32; 3],
    /// The triangle's primitive within its mesh (its draw is the instance's first draw plus this),
    /// with [`ALPHA_MASKED`] set for alpha-masked materials.
    pub draw_offset: u32,
    /// v1 − v0.
    pub e1: [f32; 3],
    /// The triangle's index within its primitive: its indices start at the draw's
    /// `first_index + 3 · triangle`.
    pub triangle: u32,
    /// v2 − v0.
    pub e2: [f32; 3],
    pub _pad: u32,
}

/// One mesh instance in the top level. Keep in sync with `RayInstance` in `rays/ray_types.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct RayInstance {
    /// Rows of the affine map from the world into the mesh's space, applied as
    /// `vec4(p, 1.0) * local_from_world`. Rays keep their parameter: a direction is mapped, not
    /// normalised, so hit distances compare across instances.
    pub local_from_world: [[f32; 4]; 3],
    /// The root of its mesh's BLAS in the node array.
    pub blas_root: u32,
    /// The scene instance's first draw (`gpu::scene::GpuDraw`): its primitives' draws follow in order.
    pub first_draw: u32,
    /// The scene instance it places (`Scene::instances`).
    pub scene_instance: u32,
    /// The first triangle of its BLAS in `RayStructure::triangles`: the hardware back end's BLAS holds
    /// the same triangles in the same order (`rays/hardware.rs`).
    pub first_triangle: u32,
}

/// The scene's ray-tracing hierarchy as uploaded: the TLAS's nodes first (root at 0), then every
/// BLAS; triangles in leaf order, BLAS after BLAS; instances in TLAS leaf order.
#[derive(Clone, Debug, Default)]
pub struct RayStructure {
    pub nodes: Vec<BvhNode>,
    pub triangles: Vec<RayTriangle>,
    pub instances: Vec<RayInstance>,
    /// Nodes of the top level, at the start of `nodes`: 2n − 1 for n instances, whatever their places.
    pub tlas_node_count: usize,
    /// CPU time of the BLAS builds and of the last TLAS build, in milliseconds.
    pub blas_build_ms: f64,
    pub tlas_build_ms: f64,
    /// Every instance the top level places, in scene order.
    placements: Vec<Placement>,
    /// The BLASes of deformed meshes (`scene::deform`), each stored twice and refitted on the GPU.
    pub deformed: Vec<DeformedBlas>,
    /// Every stored BLAS, in the order of `nodes` (and so of their roots).
    pub blases: Vec<BlasSpan>,
}

/// Where a stored BLAS lies: its root node and its triangles, in leaf order.
#[derive(Clone, Debug, PartialEq)]
pub struct BlasSpan {
    pub root: u32,
    pub triangles: std::ops::Range<u32>,
    /// It holds alpha-masked triangles: a ray must test their material's alpha.
    pub alpha_masked: bool,
}

/// A deformed mesh's BLAS, stored twice: a frame refits one copy on the GPU (`rays/refit.rs`) before
/// its passes trace it, and its top level places the mesh's instances on that copy; the next frame
/// refits the other. So a frame's refit never writes the hierarchy an earlier frame traces — on one
/// wgpu queue, which runs submissions in order, that holds anyway; it is what lets a frame's build
/// overlap the previous frame's tracing where a GPU runs them concurrently, and it keeps each frame's
/// hierarchy intact after the frame for test mode's check (`Renderer::check_ray_hierarchy`).
#[derive(Clone, Debug)]
pub struct DeformedBlas {
    pub mesh: usize,
    pub deformer: crate::scene::deform::Deformer,
    /// Each copy's root node and range of triangles.
    pub roots: [u32; 2],
    pub triangles: [std::ops::Range<u32>; 2],
    /// Each copy's nodes, children before parents (deepest first).
    pub refit_order: [Vec<u32>; 2],
    /// A box, in the space the mesh is deformed in, holding it as the frame deforms it, so the top
    /// level can be built on the CPU before the GPU refits: a wave's rest box grown by its amplitude,
    /// a pose's box at the frame's time (`set_time`).
    pub bounds: Aabb,
    /// What its boxes are made from.
    reach: crate::scene::deform::DeformedReach,
    /// The mesh's vertices at rest, primitive after primitive, and each stored triangle's corners
    /// among them, in the copies' order: the CPU reference the refit is checked against
    /// (`deformed_triangles`).
    pub rest: Vec<crate::scene::Vertex>,
    pub corners: Vec<[u32; 3]>,
}

impl DeformedBlas {
    /// The mesh's triangles deformed to `time` on the CPU, as the refit must have stored them.
    pub fn deformed_triangles(&self, time: f32, animation: Option<&crate::scene::animation::Animation>) -> Vec<RayTriangle> {
        let deformed = self.deformer.deformed(&self.rest, time, animation);
        self.corners
            .iter()
            .map(|corners| {
                let [v0, v1, v2] = corners.map(|c| Vec3::from(deformed[c as usize].position));
                RayTriangle { v0: v0.to_array(), draw_offset: 0, e1: (v1 - v0).to_array(), triangle: 0, e2: (v2 - v0).to_array(), _pad: 0 }
            })
            .collect()
    }

    /// Whether a pose deforms it (whose box moves with the animation).
    pub fn is_posed(&self) -> bool {
        self.reach.is_posed()
    }

    /// Moves a pose's box to the clock's time; a wave's holds every time.
    pub fn set_time(&mut self, clock: &crate::scene::deform::PoseClock) {
        self.bounds = self.reach.bounds(&self.deformer, clock);
    }
}

/// A mesh instance as the top level places it: its BLAS and that BLAS's box in its own space (a
/// deformed mesh's is its `DeformedBlas::bounds`).
#[derive(Clone, Copy, Debug)]
struct Placement {
    scene_instance: usize,
    blas_root: u32,
    bounds: Aabb,
    /// Its triangles were built in world space (its transform was singular at load): it stays there.
    baked: bool,
    first_draw: u32,
    /// Its mesh is deformed: `RayStructure::deformed`'s entry, whose copies it is placed on.
    deformed: Option<usize>,
}

/// What was built for rays, and how long it took: for reports.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RayStructureStats {
    pub triangles: usize,
    pub instances: usize,
    pub nodes: usize,
    pub blas_build_ms: f64,
    pub tlas_build_ms: f64,
}

/// A BLAS while the structure is assembled: its nodes (links local to it) and triangles.
struct Blas {
    bvh: Bvh,
    triangles: Vec<RayTriangle>,
}

fn invertible(t: &Affine3A) -> bool {
    let det = t.matrix3.determinant();
    det.is_finite() && det.abs() > f32::MIN_POSITIVE
}

impl RayStructure {
    pub fn stats(&self) -> RayStructureStats {
        RayStructureStats {
            triangles: self.triangles.len(),
            instances: self.instances.len(),
            nodes: self.nodes.len(),
            blas_build_ms: self.blas_build_ms,
            tlas_build_ms: self.tlas_build_ms,
        }
    }

    /// Builds the BLAS of every instanced mesh and the TLAS over the instances, at the instances'
    /// transforms. A still instance whose transform cannot be inverted (a mesh flattened onto a plane
    /// or a line) gets a BLAS of its own over its triangles in world space, placed by the identity;
    /// animated instances always use their mesh's, since they may unfold later.
    /// Meshes without opaque or alpha-masked triangles are left out.
    pub fn build(scene: &Scene) -> Result<Self> {
        let start = std::time::Instant::now();
        let mut animated = vec![false; scene.instances.len()];
        for &(instance, _) in scene.animation.iter().flat_map(|a| &a.instances) {
            animated[instance] = true;
        }
        // Deformed meshes are refitted in their own space, and their instances placed on them.
        let mut deformer_of = vec![None; scene.meshes.len()];
        for deformer in &scene.deformers {
            deformer_of[deformer.mesh] = Some(deformer);
        }
        for (instance, mesh) in scene.instances.iter().map(|i| i.mesh).enumerate() {
            animated[instance] |= deformer_of[mesh].is_some();
        }
        let in_mesh_space: Vec<bool> =
            scene.instances.iter().zip(&animated).map(|(i, &a)| a || invertible(&Affine3A::from_mat4(i.world_from_local))).collect();
        let mut shared = vec![false; scene.meshes.len()];
        for (instance, &mesh_space) in scene.instances.iter().zip(&in_mesh_space) {
            shared[instance.mesh] |= mesh_space;
        }
        // BLASes: one per mesh placed by an invertible transform, then one per singular instance.
        let mut blases = Vec::new();
        let mut mesh_blas = vec![None; scene.meshes.len()];
        // Deformed meshes' BLASes twice (`DeformedBlas`): every first copy, then every second, so each
        // copy's triangles are one range the refit covers in one dispatch.
        let mut deformed_blas = Vec::new();
        for (m, _) in shared.iter().enumerate().filter(|(_, &shared)| shared) {
            if let Some(blas) = build_blas(scene, m, &Affine3A::IDENTITY)? {
                match deformer_of[m] {
                    Some(deformer) => deformed_blas.push((deformer, blas)),
                    None => {
                        mesh_blas[m] = Some(blases.len());
                        blases.push(blas);
                    }
                }
            }
        }
        let first_copies = blases.len();
        for (deformer, blas) in &deformed_blas {
            mesh_blas[deformer.mesh] = Some(blases.len());
            blases.push(Blas { bvh: blas.bvh.clone(), triangles: blas.triangles.clone() });
        }
        let deformed_blas: Vec<_> = deformed_blas
            .into_iter()
            .enumerate()
            .map(|(i, (deformer, blas))| {
                blases.push(blas);
                (deformer, first_copies + i, blases.len() - 1)
            })
            .collect();
        let mut instance_blas = Vec::with_capacity(scene.instances.len());
        for (instance, &mesh_space) in scene.instances.iter().zip(&in_mesh_space) {
            if mesh_space {
                instance_blas.push(mesh_blas[instance.mesh].map(|b| (b, false)));
            } else {
                let blas = build_blas(scene, instance.mesh, &Affine3A::from_mat4(instance.world_from_local))?;
                instance_blas.push(blas.map(|blas| {
                    blases.push(blas);
                    (blases.len() - 1, true)
                }));
            }
        }
        let blas_build_ms = start.elapsed().as_secs_f64() * 1e3;

        // Lay out: room for the TLAS (2n − 1 nodes for n instances), then each BLAS; triangles BLAS
        // after BLAS.
        let placed = instance_blas.iter().filter(|b| b.is_some()).count();
        let tlas_node_count = (2 * placed).saturating_sub(1);
        let mut nodes = vec![BvhNode::default(); tlas_node_count];
        let mut triangles = Vec::new();
        let mut blas_roots = Vec::with_capacity(blases.len());
        let mut blas_triangles = Vec::with_capacity(blases.len());
        for blas in &blases {
            blas_roots.push(nodes.len() as u32);
            let (node_offset, triangle_offset) = (nodes.len() as u32, triangles.len() as u32);
            nodes.extend(blas.bvh.nodes.iter().map(|n| n.offset(node_offset, triangle_offset)));
            triangles.extend_from_slice(&blas.triangles);
            blas_triangles.push(triangle_offset..triangles.len() as u32);
        }
        let deformed: Vec<DeformedBlas> = deformed_blas
            .iter()
            .map(|&(deformer, b, second)| {
                let mesh = &scene.meshes[deformer.mesh];
                let roots = [blas_roots[b], blas_roots[second]];
                let order = refit_order(&nodes, roots[0]);
                let shift = roots[1] - roots[0];
                // Each primitive's first vertex among the mesh's.
                let first_vertex: Vec<u32> = mesh
                    .primitives
                    .iter()
                    .scan(0u32, |first, p| {
                        let this = *first;
                        *first += p.vertices.len() as u32;
                        Some(this)
                    })
                    .collect();
                let corners = blases[b]
                    .triangles
                    .iter()
                    .map(|t| {
                        let p = (t.draw_offset & !ALPHA_MASKED) as usize;
                        let first = 3 * t.triangle as usize;
                        [0, 1, 2].map(|k| first_vertex[p] + mesh.primitives[p].indices[first + k])
                    })
                    .collect();
                let rest: Vec<crate::scene::Vertex> = mesh.primitives.iter().flat_map(|p| p.vertices.iter().copied()).collect();
                let reach = deformer.reach(&rest);
                let mut deformed = DeformedBlas {
                    mesh: deformer.mesh,
                    deformer: deformer.clone(),
                    roots,
                    triangles: [blas_triangles[b].clone(), blas_triangles[second].clone()],
                    refit_order: [order.clone(), order.iter().map(|n| n + shift).collect()],
                    bounds: Aabb::EMPTY,
                    reach,
                    rest,
                    corners,
                };
                deformed.set_time(&crate::scene::deform::PoseClock::at(0.0, scene.animation.as_ref()));
                deformed
            })
            .collect();
        if triangles.len() > crate::accel::bvh::MAX_PRIMITIVES {
            return Err(Error::InvalidScene(format!(
                "the scene has {} triangles to trace; the ray structure holds at most {}",
                triangles.len(),
                crate::accel::bvh::MAX_PRIMITIVES
            )));
        }
        // Each scene instance's draws start after the draws of the instances before it: one per
        // primitive, in the order `GpuScene::upload` makes them.
        let mut first_draw = 0u32;
        let mut placements = Vec::with_capacity(placed);
        for (i, (instance, blas)) in scene.instances.iter().zip(&instance_blas).enumerate() {
            if let Some((b, baked)) = *blas {
                let deformed_index = deformed.iter().position(|d| d.mesh == instance.mesh && !baked);
                let bounds = blases[b].bvh.nodes[0].bounds();
                placements.push(Placement {
                    scene_instance: i,
                    blas_root: blas_roots[b],
                    bounds,
                    baked,
                    first_draw,
                    deformed: deformed_index,
                });
            }
            first_draw += scene.meshes[instance.mesh].primitives.len() as u32;
        }
        let blases = blas_roots
            .iter()
            .zip(&blas_triangles)
            .map(|(&root, range)| BlasSpan {
                root,
                triangles: range.clone(),
                alpha_masked: triangles[range.start as usize..range.end as usize].iter().any(|t| t.draw_offset & ALPHA_MASKED != 0),
            })
            .collect();
        let mut structure = Self {
            nodes,
            triangles,
            instances: Vec::new(),
            tlas_node_count,
            blas_build_ms,
            tlas_build_ms: 0.0,
            placements,
            deformed,
            blases,
        };
        structure.place(&scene.instances.iter().map(|i| i.world_from_local).collect::<Vec<_>>(), 0)?;
        Ok(structure)
    }

    /// A hierarchy in which no ray hits anything, for frames that trace no rays (bindings cannot be
    /// empty): one leaf, at the origin, of the zeroed instance the upload pads empty arrays with; its
    /// zero map stops every ray at the origin, where the root (also its BLAS) holds the zeroed
    /// triangle, which has no area. A walk through it ends after that one test.
    /// The hierarchy as the scene's bindings hold it (`GpuScene::upload`).
    pub fn buffers(&self) -> RayBuffers<'_> {
        RayBuffers {
            tlas: None,
            nodes: Records::of(&self.nodes),
            top_level_nodes: self.tlas_node_count,
            triangles: Records::of(&self.triangles),
            instances: Records::of(&self.instances),
        }
    }

    pub fn unused() -> Self {
        let leaf = BvhNode { min: [0.0; 3], max: [0.0; 3], entry: BvhNode::leaf_entry(0, 1), skip: crate::accel::END };
        Self { nodes: vec![leaf], ..Default::default() }
    }

    /// Rebuilds the top level for the scene's instances at `transforms` (world from local, one per
    /// scene instance), deformed meshes' instances on their copy `parity` (0 or 1):
    /// `nodes[..tlas_node_count]` and `instances` change, the BLASes stay. An instance whose transform
    /// is singular now is placed where no ray meets it (a point box, and a map sending every ray to a
    /// standstill); one baked in world space at load stays there.
    pub fn place(&mut self, transforms: &[glam::Mat4], parity: usize) -> Result<()> {
        let start = std::time::Instant::now();
        let mut boxes = Vec::with_capacity(self.placements.len());
        let mut maps = Vec::with_capacity(self.placements.len());
        for placement in &self.placements {
            let world_from_local =
                if placement.baked { Affine3A::IDENTITY } else { Affine3A::from_mat4(transforms[placement.scene_instance]) };
            if invertible(&world_from_local) {
                let bounds = placement.deformed.map_or(placement.bounds, |d| self.deformed[d].bounds);
                boxes.push(bounds.transformed(&world_from_local));
                maps.push(world_from_local.inverse());
            } else {
                boxes.push(Aabb::new(world_from_local.translation.into(), world_from_local.translation.into()));
                maps.push(Affine3A::ZERO);
            }
        }
        let tlas = Bvh::build_with_leaf_size(&boxes, 1)?;
        debug_assert_eq!(tlas.nodes.len(), self.tlas_node_count);
        self.nodes[..tlas.nodes.len()].copy_from_slice(&tlas.nodes);
        // TLAS leaves name their instance directly: instances are stored in leaf order.
        self.instances.clear();
        for node in self.nodes[..tlas.nodes.len()].iter_mut().filter(|n| n.is_leaf()) {
            let p = tlas.primitive_indices[node.leaf_first() as usize] as usize;
            let placement = &self.placements[p];
            *node = BvhNode { entry: BvhNode::leaf_entry(self.instances.len() as u32, 1), ..*node };
            let blas_root = placement.deformed.map_or(placement.blas_root, |d| self.deformed[d].roots[parity]);
            self.instances.push(RayInstance {
                local_from_world: crate::gpu::scene::affine_rows(&maps[p]),
                blas_root,
                first_draw: placement.first_draw,
                scene_instance: placement.scene_instance as u32,
                first_triangle: first_triangle(&self.blases, blas_root),
            });
        }
        self.tlas_build_ms = start.elapsed().as_secs_f64() * 1e3;
        Ok(())
    }

    /// The place in `blases` of the stored BLAS whose root is node `root`.
    pub fn blas_index(&self, root: u32) -> Option<usize> {
        self.blases.binary_search_by_key(&root, |b| b.root).ok()
    }

    /// The BLAS of mesh instance `instance` (in `instances`) as a standalone BVH with its triangles'
    /// boxes, for validation: links and leaf ranges moved back to start at 0.
    pub fn blas_of(&self, instance: usize) -> (Bvh, Vec<Aabb>) {
        let root = self.instances[instance].blas_root;
        // A BLAS ends at its root's skip (END); its nodes are contiguous from the root, depth first.
        let mut end = root as usize + 1;
        let mut first_triangle = u32::MAX;
        let mut last_triangle = 0;
        let mut pending = 1usize;
        let mut n = root as usize;
        // Walk the subtree in layout order: each internal node adds one pending child.
        while pending > 0 {
            let node = &self.nodes[n];
            pending -= 1;
            if node.is_leaf() {
                let range = node.leaf_range();
                first_triangle = first_triangle.min(range.start as u32);
                last_triangle = last_triangle.max(range.end as u32);
            } else {
                pending += 2;
            }
            n += 1;
            end = n;
        }
        let node_shift = root.wrapping_neg();
        let triangle_shift = first_triangle.wrapping_neg();
        let nodes: Vec<BvhNode> = self.nodes[root as usize..end].iter().map(|n| n.offset(node_shift, triangle_shift)).collect();
        let triangles = &self.triangles[first_triangle as usize..last_triangle as usize];
        let boxes = triangles.iter().map(RayTriangle::bounds).collect();
        (Bvh { nodes, primitive_indices: (0..triangles.len() as u32).collect() }, boxes)
    }
}

/// The first triangle of the stored BLAS whose root is node `root` (0 for none).
fn first_triangle(blases: &[BlasSpan], root: u32) -> u32 {
    blases.binary_search_by_key(&root, |b| b.root).map_or(0, |i| blases[i].triangles.start)
}

/// The nodes of the tree at `root` (in `nodes`, links absolute), deepest first: children always come
/// before their parents.
fn refit_order(nodes: &[BvhNode], root: u32) -> Vec<u32> {
    let mut by_depth: Vec<Vec<u32>> = Vec::new();
    let mut stack = vec![(root, 0usize)];
    while let Some((n, depth)) = stack.pop() {
        if by_depth.len() <= depth {
            by_depth.resize_with(depth + 1, Vec::new);
        }
        by_depth[depth].push(n);
        let node = &nodes[n as usize];
        if !node.is_leaf() {
            let first = node.entry;
            stack.push((first, depth + 1));
            stack.push((nodes[first as usize].skip, depth + 1));
        }
    }
    by_depth.into_iter().rev().flatten().collect()
}

impl RayTriangle {
    /// The box around the triangle, in its mesh's space.
    pub fn bounds(&self) -> Aabb {
        let v0 = Vec3::from(self.v0);
        let (v1, v2) = (v0 + Vec3::from(self.e1), v0 + Vec3::from(self.e2));
        Aabb::new(v0.min(v1).min(v2), v0.max(v1).max(v2))
    }
}

/// The BLAS over mesh `m`'s opaque and alpha-masked triangles under `transform`; `None` when it
/// has none.
fn build_blas(scene: &Scene, m: usize, transform: &Affine3A) -> Result<Option<Blas>> {
    let mesh = &scene.meshes[m];
    let mut triangles = Vec::new();
    for (p, primitive) in mesh.primitives.iter().enumerate() {
        let material = &scene.materials[primitive.material];
        if material.drawn_over_opaque() {
            continue;
        }
        let flags = if matches!(material.alpha_mode, AlphaMode::Mask { .. }) { ALPHA_MASKED } else { 0 };
        for (t, corners) in primitive.indices.chunks_exact(3).enumerate() {
            let [v0, v1, v2] = [0, 1, 2].map(|k| transform.transform_point3(Vec3::from(primitive.vertices[corners[k] as usize].position)));
            triangles.push(RayTriangle {
                v0: v0.to_array(),
                draw_offset: p as u32 | flags,
                e1: (v1 - v0).to_array(),
                triangle: t as u32,
                e2: (v2 - v0).to_array(),
                _pad: 0,
            });
        }
    }
    if triangles.is_empty() {
        return Ok(None);
    }
    let boxes: Vec<Aabb> = triangles.iter().map(RayTriangle::bounds).collect();
    let bvh = Bvh::build_with_leaf_size(&boxes, BLAS_LEAF_SIZE)
        .map_err(|e| Error::InvalidScene(format!("mesh {m} ({}): cannot build its ray hierarchy: {e}", mesh.name)))?;
    // Triangles in leaf order, so each leaf names its own contiguous range.
    let triangles = bvh.primitive_indices.iter().map(|&i| triangles[i as usize]).collect();
    Ok(Some(Blas { bvh: Bvh { primitive_indices: (0..boxes.len() as u32).collect(), ..bvh }, triangles }))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::test_support::assets_dir;

    /// Every BLAS and the TLAS of a structure pass the checks the GPU traversal relies on, and
    /// together they hold every opaque and masked triangle of every instance.
    fn check(scene: &Scene) {
        let structure = RayStructure::build(scene).unwrap();
        let mut world_boxes = Vec::new();
        let mut triangles = 0;
        for (i, instance) in structure.instances.iter().enumerate() {
            let (blas, boxes) = structure.blas_of(i);
            blas.validate(&boxes).unwrap_or_else(|e| panic!("BLAS of instance {i}: {e}"));
            // The top level bounds each instance by its BLAS's box under the scene's transform (the
            // identity for an instance built in world space).
            let identity = instance.local_from_world == crate::gpu::scene::affine_rows(&Affine3A::IDENTITY);
            let world_from_local = scene.instances[instance.scene_instance as usize].world_from_local;
            let transform = if identity { Affine3A::IDENTITY } else { Affine3A::from_mat4(world_from_local) };
            world_boxes.push(blas.nodes[0].bounds().transformed(&transform));
            triangles += boxes.len();
        }
        let tlas = Bvh {
            nodes: structure.nodes[..structure.tlas_node_count].to_vec(),
            primitive_indices: (0..structure.instances.len() as u32).collect(),
        };
        tlas.validate(&world_boxes).unwrap();
        let expected: usize = scene
            .instances
            .iter()
            .flat_map(|i| &scene.meshes[i.mesh].primitives)
            .filter(|p| !scene.materials[p.material].drawn_over_opaque())
            .map(|p| p.triangle_count())
            .sum();
        assert_eq!(triangles, expected);
    }

    #[test]
    fn sponza_and_the_gas_station_have_valid_hierarchies_holding_every_triangle() {
        for path in ["sponza/Sponza.gltf", "gas_station/GasStation.gltf"] {
            check(&crate::scene::load_path(&assets_dir().join(path)).unwrap());
        }
    }

    #[test]
    fn a_deformed_mesh_has_two_identical_copies_refitted_children_before_parents() {
        let mut scene = crate::scene::load_path(&assets_dir().join("duck/Duck.glb")).unwrap();
        let wave = crate::scene::deform::Wave { amplitude: 3.0, wavelength: 50.0, speed: 1.0, direction: Vec3::X };
        scene.deformers.push(crate::scene::deform::Deformer::wave(0, wave));
        let structure = RayStructure::build(&scene).unwrap();
        let [deformed] = &structure.deformed[..] else { panic!() };
        let [a, b] = deformed.roots.map(|r| r as usize);
        let node_count = deformed.refit_order[0].len();
        let shift = |n: &BvhNode, by: u32| n.offset(by, deformed.triangles[1].start - deformed.triangles[0].start);
        for k in 0..node_count {
            assert_eq!(shift(&structure.nodes[a + k], (b - a) as u32), structure.nodes[b + k], "node {k} of the copies");
        }
        let (t0, t1) = (&deformed.triangles[0], &deformed.triangles[1]);
        assert_eq!(structure.triangles[t0.start as usize..t0.end as usize], structure.triangles[t1.start as usize..t1.end as usize]);
        // Every node of a copy once, each after its children.
        for order in &deformed.refit_order {
            let mut seen = std::collections::HashSet::new();
            for &n in order {
                let node = &structure.nodes[n as usize];
                if !node.is_leaf() {
                    let first = node.entry;
                    assert!(seen.contains(&first) && seen.contains(&structure.nodes[first as usize].skip), "node {n} before its children");
                }
                assert!(seen.insert(n));
            }
            assert_eq!(seen.len(), node_count);
        }
        // The top level's box for it holds the mesh however the wave moves it, and lies within the
        // rest box grown by the amplitude (padded for rounding).
        let rest = structure.blas_of(0).0.nodes[0].bounds();
        let pad = Vec3::splat(3.0 + 1e-3 * rest.diagonal());
        assert!(Aabb::new(rest.min - pad, rest.max + pad).contains_box(&deformed.bounds));
        for time in [0.0, 0.7, 13.0, 31.4] {
            let triangles = deformed.deformed_triangles(time, None);
            assert_eq!(triangles.len(), (t0.end - t0.start) as usize);
            for t in triangles {
                let v0 = Vec3::from(t.v0);
                for p in [v0, v0 + Vec3::from(t.e1), v0 + Vec3::from(t.e2)] {
                    assert!(deformed.bounds.contains(p), "{p} at {time} s outside {:?}", deformed.bounds);
                }
            }
        }
    }

    #[test]
    fn a_scene_without_triangles_has_an_empty_hierarchy() {
        let structure = RayStructure::build(&Scene::default()).unwrap();
        assert!(structure.nodes.is_empty() && structure.instances.is_empty() && structure.triangles.is_empty());
    }
}
