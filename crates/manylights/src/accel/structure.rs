//! The two-level acceleration structure over the volumes of lights or of decals, the paper's TLAS
//! over BLASes: each group of volumes has a BVH in its own space (built once on the CPU, or on the
//! GPU whenever it must be rebuilt), and a top level over the group instances, rebuilt whenever an
//! instance moves (on the CPU up to [`CPU_TOP_LEVEL_MAX_INSTANCES`] instances, on the GPU above),
//! places them in the world. Moving or instancing a group never touches its BVH.
//!
//! One bind group per structure, read by `accel/volume_query.wgsl` and the enumeration modules:
//! `items` (lights or decals, group after group, each in its group's space and in its BVH's leaf
//! order, so a group leaf names the range of items it holds), `nodes` (the top level first, then each
//! group's entry-grid header node and BVH), `primitives` (the top level's instance indices, then each
//! item's index in the scene, then the CPU-built groups' entry grids, `entry_grid.rs`, or cell lists,
//! `cell_lists.rs`) and
//! `instances`. Sharing one node array between all BVHs keeps the binding count fixed; a structure
//! over 1M volumes still stays under lavapipe's 128 MiB per binding.
//!
//! Items in leaf order save the query an index load per item and put a leaf's items side by side. A
//! CPU-built group is uploaded in that order; a group rebuilt on the GPU is put in it after each build
//! (`leaf_order.rs`), and the dynamic group by the pass that writes it.

use std::ops::Range;

use bytemuck::Zeroable;
use glam::Affine3A;

use super::{
    bvh::{MAX_LEAF_SIZE, MAX_PRIMITIVES},
    cell_lists::{self, CellLists},
    clusters::{ClusterBounds, ClusterLists, ClusterNames, Clustering},
    decal_aabb,
    entry_grid::{self, EntryGrid},
    hardware::{DynamicBoxes, HardwareScopes, HardwareVolumes},
    lbvh::{GpuLbvh, LbvhTarget, TimerSpan},
    leaf_order::{LeafOrder, LeafOrderTarget},
    light_aabb,
    light_tree::{light_tree_nodes, LightTreeNode},
    rebuilt_cell_lists::{ListBounds, ListPlacement, RebuiltCellLists},
    rebuilt_grid::{GridPlacement, RebuiltGrids, RebuiltGroup},
    Aabb, Bvh, BvhNode,
};
use crate::{
    gpu::{
        bindings,
        cluster_grid::ClusterGrid,
        scene::{affine_rows, GpuDecal, GpuLight},
        GpuContext, GpuTimer,
    },
    plan::{DynamicLeaves, GroupBuild, GroupLists, StructurePlan},
    scene::{Decal, GroupInstance, Groups, Light, DECAL_LAYERS},
    Error, Result,
};

/// Up to this many instances the top level is built on the CPU (binned SAH, one instance per leaf)
/// and uploaded with the instances, which takes microseconds; a GPU build has a fixed cost of its
/// passes, larger than a CPU build of a small top level. Above it, the GPU builds the top level.
pub const CPU_TOP_LEVEL_MAX_INSTANCES: usize = 1024;

/// Keep in sync with `VolumeInstance` in `accel/bvh_types.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GpuVolumeInstance {
    /// Rows of the affine map from the world into the group's space.
    pub group_from_world: [[f32; 4]; 3],
    /// Rows of its inverse.
    pub world_from_group: [[f32; 4]; 3],
    pub first_item: u32,
    pub item_count: u32,
    /// Node index of the group's BVH root.
    pub blas_root: u32,
    /// Uniform scale of `world_from_group`: ranges grow with it.
    pub scale: f32,
}

/// Instance 0 and its group's entry-grid or cell-list header (zero without either), in a uniform buffer: a query over
/// a lone instance starts from them without two dependent storage loads before its first node, which
/// the fragment stage waits for (benchmarks/LOG.md, topic 4). Keep in sync with
/// `FirstInstance` in `accel/bvh_types.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
struct GpuFirstInstance {
    instance: GpuVolumeInstance,
    entry_grid_header: BvhNode,
}

/// Set in `GpuVolumeInstance::blas_root` when the group has an entry grid (`entry_grid.rs`), whose
/// header is the node before the root.
pub const ENTRY_GRID_FLAG: u32 = 1 << 31;

impl GpuVolumeInstance {
    fn new(world_from_group: Affine3A, group: &Group) -> Self {
        Self {
            group_from_world: affine_rows(&world_from_group.inverse()),
            world_from_group: affine_rows(&world_from_group),
            first_item: group.items.start,
            item_count: group.items.len() as u32,
            blas_root: group.blas_root | group.grid.map_or(0, |g| g.flag),
            scale: world_from_group.matrix3.x_axis.length(),
        }
    }
}

/// What a CPU-built group's queries read before its BVH, if anything: where to start in it, or the
/// lists that replace it.
enum GroupGrid {
    Entry(EntryGrid),
    Lists(CellLists),
}

impl GroupGrid {
    /// Words of the primitive array it takes.
    fn gpu_len(&self) -> usize {
        match self {
            GroupGrid::Entry(grid) => grid.gpu_len(),
            GroupGrid::Lists(lists) => lists.gpu_len(),
        }
    }

    /// Its words from word `first_cell` of the primitive array, for the group whose root is node
    /// `blas_root` and first item `first_item`, and the header node that describes it: its corner
    /// (`min`), its first cell's index in the primitives array (`entry`), cells per unit length (`max`)
    /// and cells per axis, 10 bits each, x lowest (`skip`). Keep in sync with `entry_grid_cell` in
    /// `accel/bvh_types.wgsl`.
    fn gpu_words(&self, blas_root: u32, first_item: u32, first_cell: u32) -> (Vec<u32>, GridHeader) {
        let (words, min, cells_per_unit, dims, flag) = match self {
            GroupGrid::Entry(grid) => {
                (grid.gpu_words(blas_root, first_cell), grid.min, grid.cells_per_unit, grid.packed_dims(), ENTRY_GRID_FLAG)
            }
            // No flag: a walk of the group ignores its lists and starts at its root.
            GroupGrid::Lists(lists) => (lists.gpu_words(first_item, first_cell), lists.min, lists.cells_per_unit, lists.packed_dims(), 0),
        };
        let node = BvhNode { min: min.to_array(), entry: first_cell, max: cells_per_unit.to_array(), skip: dims };
        (words, GridHeader { node, flag })
    }
}

/// The node before a group's root that describes its entry grid or cell lists, and the flag set in its
/// instances' `blas_root` for an entry grid, which walks start from.
#[derive(Clone, Copy, Debug)]
struct GridHeader {
    node: BvhNode,
    flag: u32,
}

/// Cell lists over a group of decals (`boxes` and `records` by item): each cell lists the decals whose
/// oriented box may reach it ([`decal_may_reach`]), top layer first and by item within a layer, each
/// entry with its layer (`CellLists::sort_lists_by_rank`), as `decals_bvh_cells.wgsl` reads them.
fn decal_cell_lists(boxes: &[Aabb], records: &[GpuDecal], budget_words: usize) -> Option<CellLists> {
    let may_reach = |item: usize, cell: &Aabb| decal_may_reach(&records[item].decal_from_group, cell);
    let mut lists = CellLists::build(boxes, &may_reach, budget_words)?;
    let layers: Vec<u32> = records.iter().map(|r| r.layer.min(DECAL_LAYERS - 1)).collect();
    lists.sort_lists_by_rank(|item| layers[item as usize]);
    Some(lists)
}

/// Whether a decal's box, with rows `decal_from_group` (`GpuDecal`), may reach `cell`: along each of
/// the decal's axes, the cell's centre lies within the decal's half-width plus the cell's reach
/// (the decal's three separating axes; the cell's are its box's, which the caller has tested).
fn decal_may_reach(decal_from_group: &[[f32; 4]; 3], cell: &Aabb) -> bool {
    let centre = (cell.min + cell.max) * 0.5;
    let half = (cell.max - cell.min) * 0.5;
    decal_from_group.iter().all(|row| {
        let axis = glam::Vec3::new(row[0], row[1], row[2]);
        let reach = axis.abs().dot(half);
        // A ten-thousandth of the decal and of the cell's reach, in decal units, for rounding: the
        // coordinates are f32 around the group's origin, the test is conservative either way.
        (axis.dot(centre) + row[3]).abs() <= 0.5 + reach + 1e-4 * (1.0 + reach)
    })
}

/// A group's items and its BVH in the shared arrays.
struct Group {
    items: Range<u32>,
    blas_root: u32,
    /// The header of the entry grid queries start from, or of the cell lists they read (CPU-built
    /// groups), also stored as the node before the root.
    grid: Option<GridHeader>,
    /// Written on the GPU every frame (`Volumes::dynamic`).
    dynamic: bool,
    /// Bounds of the group's volumes, in its space: the top level's boxes are their images.
    bounds: Aabb,
    /// Present when the group is rebuilt on the GPU.
    builder: Option<GpuLbvh>,
    /// The dynamic group's boxes where no LBVH is built over them (the hardware back end builds its
    /// bottom level from them); with a builder, they are its boxes.
    boxes: Option<wgpu::Buffer>,
}

/// Checks that the scene's lights and decals, in their groups' instances, fit their structures on this
/// device: what `Renderer::new` would refuse, without building anything.
pub fn check_scene_capacity(ctx: &GpuContext, scene: &crate::scene::Scene) -> Result<()> {
    for (kind, count, groups) in
        [(VolumeKind::Lights, scene.lights.len(), &scene.light_groups), (VolumeKind::Decals, scene.decals.len(), &scene.decal_groups)]
    {
        let (ranges, instances) = groups.resolve(count);
        let slots = instances.iter().filter(|i| !ranges[i.group].is_empty()).count().max(1) as u32;
        kind.check_capacity(ctx, count, 0, slots)?;
    }
    Ok(())
}

/// What a structure holds; names its buffers and timer scopes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VolumeKind {
    Lights,
    Decals,
}

impl VolumeKind {
    fn label(self) -> &'static str {
        match self {
            VolumeKind::Lights => "light",
            VolumeKind::Decals => "decal",
        }
    }

    fn scopes(self) -> Scopes {
        match self {
            VolumeKind::Lights => Scopes {
                top_level: "light_tlas_build",
                groups: "light_blas_build",
                leaf_order: "light_leaf_order",
                rebuilt_grids: "light_entry_grid_build",
                rebuilt_lists: "light_cell_lists_build",
                clusters: "light_cluster_build",
                hardware_pack: "light_hardware_boxes_build",
            },
            VolumeKind::Decals => Scopes {
                top_level: "decal_tlas_build",
                groups: "decal_blas_build",
                leaf_order: "decal_leaf_order",
                rebuilt_grids: "decal_entry_grid_build",
                rebuilt_lists: "decal_cell_lists_build",
                clusters: "decal_cluster_build",
                hardware_pack: "decal_hardware_boxes_build",
            },
        }
    }

    /// Checks, before anything is built, that `count` volumes, `dynamic_count` particle volumes and
    /// `instance_slots` group instances fit one structure and their records one storage binding.
    pub fn check_capacity(self, ctx: &GpuContext, count: usize, dynamic_count: u32, instance_slots: u32) -> Result<()> {
        let label = self.label();
        let primitive_count = u64::from(instance_slots) + count as u64 + u64::from(dynamic_count);
        if primitive_count > MAX_PRIMITIVES as u64 {
            let (particles, fewer) = if dynamic_count > 0 {
                (format!(" (and {dynamic_count} particle {label}s)"), format!("{label}s or particles"))
            } else {
                (String::new(), format!("{label}s"))
            };
            return Err(Error::InvalidScene(format!(
                "{count} {label}s{particles} and {instance_slots} instance slots; a structure holds at most {MAX_PRIMITIVES} volumes and instances: use fewer {fewer}"
            )));
        }
        // Checked before the CPU builds, which take seconds for millions of volumes.
        let item_bytes = (count as u64 + u64::from(dynamic_count)) * self.record_bytes() as u64;
        ctx.check_storage_binding(&format!("{label} items"), item_bytes)
            .map_err(|m| Error::InvalidScene(format!("{m}; use fewer {label}s")))
    }

    /// Bytes of one item's record (`GpuLight` or `GpuDecal`).
    fn record_bytes(self) -> usize {
        match self {
            VolumeKind::Lights => std::mem::size_of::<GpuLight>(),
            VolumeKind::Decals => std::mem::size_of::<GpuDecal>(),
        }
    }
}

/// A structure's timer scopes: the top-level build, the groups' rebuilds, putting rebuilt groups'
/// items in leaf order, their entry grids or cell lists, and the clustered lists.
struct Scopes {
    top_level: &'static str,
    groups: &'static str,
    leaf_order: &'static str,
    rebuilt_grids: &'static str,
    rebuilt_lists: &'static str,
    clusters: &'static str,
    /// Packing the dynamic group's boxes for the hardware back end's bottom level.
    hardware_pack: &'static str,
}

/// The volumes a structure is built over: the GPU items (one record per volume) and their boxes, in
/// group space, grouped as `groups` says.
pub struct Volumes<'a> {
    pub kind: VolumeKind,
    pub items: &'a [u8],
    pub boxes: &'a [Aabb],
    /// The CPU-built groups get wide leaves ([`Bvh::build_wide`]), for queries that share each leaf
    /// out among a subgroup's lanes (`plan::StructurePlan::wide_leaves`).
    pub wide_leaves: bool,
    /// The leaves of groups rebuilt on the GPU every frame (`plan::StructurePlan::rebuilt_leaves`).
    pub rebuilt_leaves: DynamicLeaves,
    /// Groups rebuilt on the GPU every frame get entry grids (`plan::StructurePlan::rebuilt_grids`).
    pub rebuilt_grids: bool,
    /// The one placed group gets cell lists where they fit (`plan::StructurePlan::cell_lists`): built
    /// with its BVH on the CPU (crowded decals), or on the GPU in place of its BVH, once or every
    /// frame as `build` says.
    pub cell_lists: GroupLists,
    /// Light groups get their light tree (`light_tree.rs`, `plan::StructurePlan::light_tree`): built
    /// with the CPU's BVHs, or alongside each GPU rebuild (the dynamic group's too).
    pub light_tree: bool,
    /// The groups are queried through the GPU's ray queries (`hardware.rs`,
    /// `plan::StructurePlan::hardware`) instead of walked: no software BVH is built.
    pub hardware: bool,
    pub groups: &'a Groups,
    /// Volumes written on the GPU every frame, after the others: one more group, placed at identity
    /// and rebuilt on the GPU every frame (particle lights, `particles/`).
    pub dynamic: Option<DynamicGroup>,
}

/// A group whose items and boxes a GPU pass writes every frame ([`VolumeStructure::dynamic_group`]).
#[derive(Clone, Copy, Debug)]
pub struct DynamicGroup {
    pub count: u32,
    /// Bounds every one of its boxes stays within (its place in the top level).
    pub bounds: Aabb,
    /// How many boxes a leaf of its LBVH holds.
    pub leaves: DynamicLeaves,
}

/// Where GPU passes write a [`DynamicGroup`]'s volumes each frame: their boxes into `boxes`, before
/// the structure's `record`, and after it the items from `first_item` of `items` in leaf order: the
/// build leaves primitive `first_primitive` + k naming `first_item` + the index of the box it sorted to
/// position k, and the leaves over position k name item `first_item` + k.
/// Where the structure has a light tree, the pass also writes each box's emitter into `emitters`
/// (`accel::light_tree::LightTreeNode`, by box).
pub struct DynamicTargets<'a> {
    pub items: &'a wgpu::Buffer,
    pub first_item: u32,
    pub boxes: &'a wgpu::Buffer,
    pub primitives: &'a wgpu::Buffer,
    pub first_primitive: u32,
    pub light_tree: bool,
    pub emitters: &'a wgpu::Buffer,
}

pub struct VolumeStructure {
    pub bind_group_layout: wgpu::BindGroupLayout,
    pub bind_group: wgpu::BindGroup,
    label: &'static str,
    buffers: Buffers,
    /// Each item's decal layer (empty for lights): deferred decals draw in layer order.
    layers: Vec<u32>,
    /// The scene's index of each item but the dynamic group's, in the order they are stored: CPU-built
    /// groups' in leaf order; GPU-rebuilt groups' in scene order, as their copy into leaf order reads
    /// them (where they land changes with every build); a group listed in place of its BVH in scene
    /// order.
    scene_indices: Vec<u32>,
    /// The CPU-built groups have wide leaves ([`Volumes::wide_leaves`]).
    wide_leaves: bool,
    /// The structure's one placed group has cell lists ([`Self::cell_lists`]).
    cell_lists: bool,
    /// Builds the cell lists of the one placed group in place of its BVH, every frame or once.
    rebuilt_lists: Option<RebuiltCellLists>,
    /// Puts the items in leaf order after GPU rebuilds (none when every group is built on the CPU).
    leaf_order: Option<LeafOrder>,
    /// Rebuilds the entry grids of groups rebuilt on the GPU, after their builds.
    rebuilt_grids: Option<RebuiltGrids>,
    /// Present for the clustered method; its buffers are bindings 4 and 5, placeholders otherwise.
    clusters: Option<ClusterLists>,
    /// The acceleration structures ray queries read, with the hardware back end: bound after the
    /// other bindings ([`hardware_binding`]).
    hardware: Option<HardwareVolumes>,
    groups: Vec<Group>,
    /// Instances of non-empty groups: instances of empty groups can contain nothing.
    instances: Vec<GroupInstance>,
    /// Builds the top level on the GPU when there are more than [`CPU_TOP_LEVEL_MAX_INSTANCES`].
    top_level_builder: Option<GpuLbvh>,
    top_level_scope: &'static str,
    blas_scope: &'static str,
    /// The time the top level was last built for; `None` before the first build.
    built_for: Option<f32>,
}

/// Every (instance, item) pair in the order deferred decals draw them, and the range of pairs in each
/// layer that has any ([`VolumeStructure::pairs_in_layer_order`]).
pub type LayerOrder = (Vec<[u32; 2]>, Vec<Range<u32>>);

impl VolumeStructure {
    /// The structure over a scene's lights; with clustered lists on `clusters`' grid when given.
    pub fn for_lights(
        ctx: &GpuContext,
        lights: &[Light],
        groups: &Groups,
        plan: &StructurePlan,
        clusters: Option<(ClusterGrid, &wgpu::BindGroupLayout)>,
    ) -> Result<Self> {
        let items: Vec<GpuLight> = lights.iter().map(GpuLight::from).collect();
        let boxes: Vec<Aabb> = lights.iter().map(light_aabb).collect();
        let clustering = clusters.map(|(grid, frame_layout)| Clustering {
            grid,
            bounds: lights.iter().map(ClusterBounds::of_light).collect(),
            frame_layout,
        });
        let volumes = Volumes {
            kind: VolumeKind::Lights,
            items: bytemuck::cast_slice(&items),
            boxes: &boxes,
            wide_leaves: plan.wide_leaves,
            rebuilt_leaves: plan.rebuilt_leaves,
            rebuilt_grids: plan.rebuilt_grids,
            cell_lists: plan.cell_lists,
            light_tree: plan.light_tree,
            hardware: plan.hardware,
            groups,
            dynamic: None,
        };
        Self::new(ctx, &volumes, plan.build, clustering)
    }

    /// The structure over a scene's lights and `particle_lights` point lights more, which a GPU pass
    /// writes every frame ([`dynamic_group`](Self::dynamic_group)) within `particle_bounds`, in leaves
    /// with `leaves` as the plan says (`plan::dynamic_leaves`).
    pub fn for_lights_and_particles(
        ctx: &GpuContext,
        lights: &[Light],
        groups: &Groups,
        plan: &StructurePlan,
        particle_lights: u32,
        particle_bounds: Aabb,
        leaves: DynamicLeaves,
    ) -> Result<Self> {
        let items: Vec<GpuLight> = lights.iter().map(GpuLight::from).collect();
        let boxes: Vec<Aabb> = lights.iter().map(light_aabb).collect();
        let dynamic = DynamicGroup { count: particle_lights, bounds: particle_bounds, leaves };
        let volumes = Volumes {
            kind: VolumeKind::Lights,
            items: bytemuck::cast_slice(&items),
            boxes: &boxes,
            wide_leaves: plan.wide_leaves,
            rebuilt_leaves: plan.rebuilt_leaves,
            rebuilt_grids: plan.rebuilt_grids,
            cell_lists: GroupLists::None,
            light_tree: plan.light_tree,
            hardware: plan.hardware,
            groups,
            dynamic: Some(dynamic),
        };
        Self::new(ctx, &volumes, plan.build, None)
    }

    /// Where the GPU writes the dynamic group's volumes, if the structure has one.
    pub fn dynamic_group(&self) -> Option<DynamicTargets<'_>> {
        let group = self.groups.iter().find(|g| g.dynamic)?;
        let (boxes, first_primitive, emitters) = match (&group.builder, &group.boxes) {
            (Some(builder), _) => (builder.boxes(), builder.primitive_base(), builder.emitters()),
            // The hardware back end: the primitives name the items in box order, and no tree is built.
            (None, Some(boxes)) => (boxes, self.instance_slots() + group.items.start, &self.buffers.light_tree),
            (None, None) => return None,
        };
        Some(DynamicTargets {
            items: &self.buffers.items,
            first_item: group.items.start,
            boxes,
            primitives: &self.buffers.primitives,
            first_primitive,
            light_tree: self.buffers.builds_light_tree,
            emitters,
        })
    }

    /// The top level's primitive slots, before the items' scene indices in the primitive array.
    fn instance_slots(&self) -> u32 {
        self.instances.len().max(1) as u32
    }

    /// The structure over a scene's decals, built as `plan` says; with clustered lists on `clusters`'
    /// grid when given. Decals name their materials' records from `decal_material_base` on
    /// (`GpuScene::decal_material_base`).
    pub fn for_decals(
        ctx: &GpuContext,
        decals: &[Decal],
        groups: &Groups,
        plan: &StructurePlan,
        clusters: Option<(ClusterGrid, &wgpu::BindGroupLayout)>,
        decal_material_base: u32,
    ) -> Result<Self> {
        let items: Vec<GpuDecal> = decals.iter().map(|d| GpuDecal::new(d, decal_material_base)).collect();
        let boxes: Vec<Aabb> = decals.iter().map(decal_aabb).collect();
        let clustering = clusters.map(|(grid, frame_layout)| Clustering {
            grid,
            bounds: decals.iter().map(ClusterBounds::of_decal).collect(),
            frame_layout,
        });
        let volumes = Volumes {
            kind: VolumeKind::Decals,
            items: bytemuck::cast_slice(&items),
            boxes: &boxes,
            wide_leaves: plan.wide_leaves,
            rebuilt_leaves: plan.rebuilt_leaves,
            rebuilt_grids: plan.rebuilt_grids,
            cell_lists: plan.cell_lists,
            light_tree: false,
            hardware: plan.hardware,
            groups,
            dynamic: None,
        };
        let mut structure = Self::new(ctx, &volumes, plan.build, clustering)?;
        structure.layers = structure.scene_indices.iter().map(|&i| decals[i as usize].layer).collect();
        Ok(structure)
    }

    /// Every (instance, item) pair, instances in the order of the instance buffer, sorted stably by
    /// decal layer — the order deferred decals are drawn in, bottom layer first — and the range of
    /// pairs in each layer that has any. Errors when groups are rebuilt on the GPU: their items' order
    /// changes every frame, out of the CPU's sight.
    pub fn pairs_in_layer_order(&self) -> Result<LayerOrder> {
        if self.leaf_order.is_some() {
            return Err(Error::InvalidConfig(format!(
                "drawing {}s in layer order needs their items in a fixed order; build their BVH once on the CPU",
                self.label
            )));
        }
        let layer = |item: u32| self.layers.get(item as usize).copied().unwrap_or(0);
        let mut pairs: Vec<[u32; 2]> = self
            .instances
            .iter()
            .enumerate()
            .flat_map(|(i, instance)| self.groups[instance.group].items.clone().map(move |item| [i as u32, item]))
            .collect();
        pairs.sort_by_key(|&[_, item]| layer(item));
        let mut ranges: Vec<Range<u32>> = Vec::new();
        for (i, &[_, item]) in pairs.iter().enumerate() {
            match ranges.last_mut() {
                Some(range) if layer(pairs[range.start as usize][1]) == layer(item) => range.end = i as u32 + 1,
                _ => ranges.push(i as u32..i as u32 + 1),
            }
        }
        Ok((pairs, ranges))
    }

    /// Builds the structure over `volumes`: its groups' BVHs as `build` says, with clustered lists
    /// when `clustering` is given.
    pub fn new(ctx: &GpuContext, volumes: &Volumes, build: GroupBuild, clustering: Option<Clustering>) -> Result<Self> {
        volumes.check()?;
        let label = volumes.kind.label();
        let layout = Layout::new(volumes);
        // With the hardware back end, `build` says when wgpu builds the groups' structures; the
        // items are stored in scene order, group after group, as its bottom levels' boxes are.
        let hardware_rebuilds = build == GroupBuild::GpuEveryFrame;
        let build = if volumes.hardware { GroupBuild::None } else { build };
        volumes.kind.check_capacity(ctx, layout.count, layout.dynamic_count(), layout.instance_slots)?;
        let fits = |what: &str, bytes: u64| {
            ctx.check_storage_binding(&format!("{label} {what}"), bytes)
                .map_err(|m| Error::InvalidScene(format!("{m}; use fewer {label}s")))
        };
        // Without group BVHs only the top level's nodes are written (the hardware back end builds none
        // over the dynamic group either).
        let no_group_bvh = build == GroupBuild::None && (layout.dynamic.is_none() || volumes.hardware);
        let stored_nodes = if no_group_bvh { layout.top_level_nodes() } else { layout.node_count };
        let node_bytes = u64::from(stored_nodes) * std::mem::size_of::<BvhNode>() as u64;
        fits("BVH nodes", node_bytes)?;
        // CPU builds first: their entry grids' cells and covers, or cell lists, follow the primitive
        // indices in the same array.
        let listed = list_placement(ctx, volumes, &layout, build);
        let cpu_groups = cpu_builds(volumes, &layout, build, listed.map(|(group, _)| group))?;
        let wide_leaves = volumes.wide_leaves && cpu_groups.iter().any(Option::is_some);
        let scene_indices = stored_order(&layout.ranges, &cpu_groups);
        let rebuilt_on_gpu = build == GroupBuild::GpuEveryFrame
            && layout.ranges.iter().enumerate().any(|(g, range)| !range.is_empty() && listed.is_none_or(|(listed, _)| listed != g));
        if rebuilt_on_gpu && clustering.is_some() {
            return Err(Error::InvalidConfig(format!(
                "clustered lists bin the {label}s in the order the CPU stores them, which GPU rebuilds change every frame; build the {label}s' BVH once on the CPU"
            )));
        }
        let rebuilds = rebuilds(volumes, &layout, build, listed);
        let rebuilt_grid_cells = rebuilds.iter().filter_map(|r| match r {
            Rebuild::Lbvh(Some(grid)) => Some(2 * u64::from(grid.cells())),
            _ => None,
        });
        let cell_words: u64 = cpu_groups.iter().flatten().filter_map(|g| g.grid.as_ref()).map(|g| g.gpu_len() as u64).sum::<u64>()
            + rebuilt_grid_cells.sum::<u64>();
        let cell_lists = listed.is_some() || cpu_groups.iter().flatten().any(|g| matches!(g.grid, Some(GroupGrid::Lists(_))));
        let primitive_count = layout.primitive_count();
        if primitive_count + cell_words > u64::from(entry_grid::CELL_COVER_OFFSET_MASK) {
            return Err(Error::InvalidScene(format!(
                "{} {label}s need {} words of primitive indices, entry grids and cell lists, over the {} a structure addresses; use fewer {label}s",
                layout.count,
                primitive_count + cell_words,
                entry_grid::CELL_COVER_OFFSET_MASK
            )));
        }
        let primitive_bytes = (primitive_count + cell_words) * 4;
        fits("BVH primitives, entry grids and cell lists", primitive_bytes)?;

        let buffers = Buffers::new(ctx, volumes, &layout, node_bytes, primitive_bytes);
        let leaf_order = if rebuilt_on_gpu {
            let scope = volumes.kind.scopes().leaf_order;
            let targets =
                LeafOrderTarget { items: &buffers.items, primitives: &buffers.primitives, first_primitive: layout.instance_slots };
            Some(LeafOrder::new(ctx, scope, volumes.items, volumes.kind.record_bytes(), targets)?)
        } else {
            buffers.write_items_in_order(ctx, volumes, &scene_indices);
            None
        };
        if !scene_indices.is_empty() {
            ctx.queue.write_buffer(&buffers.primitives, u64::from(layout.instance_slots) * 4, bytemuck::cast_slice(&scene_indices));
        }
        let (mut groups, rebuilt) = place_groups(ctx, volumes, &layout, &buffers, build, cpu_groups, rebuilds)?;
        let rebuilt_lists = listed
            .map(|(group, placement)| {
                let range = &layout.ranges[group];
                let boxes = &volumes.boxes[range.clone()];
                let bounds: Vec<ListBounds> = match volumes.kind {
                    VolumeKind::Lights => {
                        let lights: &[GpuLight] = bytemuck::cast_slice(&volumes.items[group_bytes(volumes, range)]);
                        lights
                            .iter()
                            .zip(boxes)
                            .map(|(light, aabb)| ListBounds::of_light(light.position.into(), light.range, *aabb))
                            .collect()
                    }
                    VolumeKind::Decals => {
                        let decals: &[GpuDecal] = bytemuck::cast_slice(&volumes.items[group_bytes(volumes, range)]);
                        boxes.iter().zip(decals).map(|(aabb, decal)| ListBounds::of_decal(aabb, decal.decal_from_group)).collect()
                    }
                };
                let capacity = u32::try_from(placement.visits).unwrap_or(u32::MAX);
                let lists = RebuiltCellLists::new(
                    ctx,
                    label,
                    volumes.kind.scopes().rebuilt_lists,
                    placement,
                    &bounds,
                    range.start as u32,
                    capacity,
                )?;
                Ok(if build == GroupBuild::GpuEveryFrame { lists } else { lists.built_once() })
            })
            .transpose()?;
        let rebuilt_grids = (!rebuilt.is_empty())
            .then(|| RebuiltGrids::new(ctx, volumes.kind.scopes().rebuilt_grids, &buffers.nodes, &buffers.primitives, &rebuilt))
            .transpose()?;
        if let Some(dynamic) = layout.dynamic {
            groups.push(dynamic_group(ctx, &layout, &buffers, dynamic, volumes.hardware)?);
        }
        let top_level_builder = (!volumes.hardware && layout.instances.len() > CPU_TOP_LEVEL_MAX_INSTANCES)
            .then(|| GpuLbvh::with_target(ctx, layout.instance_slots, buffers.target(0, 0, 0, false)))
            .transpose()?;
        let Scopes { top_level: top_level_scope, groups: blas_scope, clusters: cluster_scope, .. } = volumes.kind.scopes();
        let clusters = match clustering {
            Some(c) => {
                let instance_items: Vec<u32> = layout.instances.iter().map(|i| layout.ranges[i.group].len() as u32).collect();
                Some(c.lists(ctx, ClusterNames { label, scope: cluster_scope }, &buffers.instances, &instance_items, &scene_indices)?)
            }
            None => None,
        };
        let hardware = if volumes.hardware {
            let group_boxes: Vec<Vec<Aabb>> = layout.ranges.iter().map(|r| volumes.boxes[r.clone()].to_vec()).collect();
            let dynamic = groups.iter().find(|g| g.dynamic).and_then(|g| g.boxes.as_ref().map(|boxes| (boxes, g.items.len() as u32)));
            let scopes = volumes.kind.scopes();
            let scopes = HardwareScopes { groups: scopes.groups, top_level: scopes.top_level, pack: scopes.hardware_pack };
            Some(HardwareVolumes::new(
                ctx,
                label,
                &group_boxes,
                dynamic.map(|(boxes, count)| DynamicBoxes { boxes, count }),
                layout.instance_slots,
                hardware_rebuilds,
                scopes,
            )?)
        } else {
            None
        };
        let bind_group_layout = shading_bind_group_layout(&ctx.device, label, hardware.is_some());
        let lists = list_buffers(clusters.as_ref(), rebuilt_lists.as_ref());
        let bind_group = shading_bind_group(ctx, label, &bind_group_layout, buffers.bound(), lists, hardware.as_ref());
        Ok(Self {
            bind_group_layout,
            bind_group,
            label,
            buffers,
            layers: Vec::new(),
            scene_indices,
            wide_leaves,
            cell_lists,
            rebuilt_lists,
            leaf_order,
            rebuilt_grids,
            clusters,
            hardware,
            groups,
            instances: layout.instances,
            top_level_builder,
            top_level_scope,
            blas_scope,
            built_for: None,
        })
    }

    /// The scene's index of each stored item but the dynamic group's: item i of the structure is the
    /// scene's light or decal `scene_indices()[i]` where its group is built on the CPU, which stores
    /// it in leaf order (or in scene order, where lists replace the group's BVH).
    pub fn scene_indices(&self) -> &[u32] {
        &self.scene_indices
    }

    /// Whether the structure is one group, placed once, with cell lists, so shading reads the list of
    /// a point's cell instead of walking: decals that crowd and whose queries share them out
    /// (`wide_leaves`), built on the CPU (`cell_lists.rs`, `shading/enumerate/decals_bvh_cells.wgsl`),
    /// whose BVH stays, for its items' order and for walks of other passes, which start at its root;
    /// or sparser lights or decals, built once or every frame (`rebuilt_cell_lists.rs`,
    /// `shading/enumerate/lights_cells.wgsl`, `decals_cells.wgsl`), whose lists replace their BVH.
    pub fn cell_lists(&self) -> bool {
        self.cell_lists
    }

    /// Whether the CPU-built groups have wide leaves ([`Volumes::wide_leaves`]): queries of this
    /// structure should share its leaves out, as the plan makes them (`plan::query_walks`); tested
    /// one by one, wide leaves are slow.
    pub fn wide_leaves(&self) -> bool {
        self.wide_leaves
    }

    /// Instances the shaders visit (those of non-empty groups).
    pub fn instance_count(&self) -> u32 {
        self.instances.len() as u32
    }

    /// Records this frame's clustered lists, if the structure has them, after `record`: they read
    /// the instances it placed and the frame uniforms of `frame`, the scene's bind group.
    pub fn record_clusters(&self, encoder: &mut wgpu::CommandEncoder, timer: Option<&mut GpuTimer>, frame: &wgpu::BindGroup) {
        if let Some(clusters) = &self.clusters {
            clusters.record(encoder, timer, frame);
        }
    }

    /// Entries the clustered lists hold, if the structure has them.
    pub fn cluster_capacity(&self) -> Option<u32> {
        self.clusters.as_ref().map(ClusterLists::capacity)
    }

    /// Whether the clustered lists or the rebuilt cell lists held everything the frames since the
    /// last call needed (always true without them). If not, they have grown, and those frames must be
    /// rendered again.
    pub fn lists_fitted(&mut self, ctx: &GpuContext) -> Result<bool> {
        let fitted = match (&mut self.clusters, &mut self.rebuilt_lists) {
            (Some(clusters), _) => clusters.fitted(ctx)?,
            (None, Some(lists)) => lists.fitted(ctx)?,
            (None, None) => true,
        };
        if fitted {
            return Ok(true);
        }
        let lists = list_buffers(self.clusters.as_ref(), self.rebuilt_lists.as_ref());
        self.bind_group = shading_bind_group(ctx, self.label, &self.bind_group_layout, self.buffers.bound(), lists, self.hardware.as_ref());
        Ok(false)
    }

    /// Records this frame's builds for time `time` (seconds): the groups rebuilt on the GPU, then the
    /// top level, when an instance has moved since the last build or a group was rebuilt.
    pub fn record(
        &mut self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        mut timer: Option<&mut GpuTimer>,
        time: f32,
    ) -> Result<()> {
        let rebuilding: Vec<usize> = (0..self.groups.len()).filter(|&g| self.groups[g].builder.is_some()).collect();
        for (k, &g) in rebuilding.iter().enumerate() {
            let span = TimerSpan { name: self.blas_scope, starts: k == 0, ends: k + 1 == rebuilding.len() };
            self.groups[g].builder.as_mut().expect("filtered on builders").record(encoder, timer.as_deref_mut(), span)?;
        }
        if let Some(lists) = &mut self.rebuilt_lists {
            lists.record(encoder, timer.as_deref_mut());
        }
        if let Some(leaf_order) = &self.leaf_order {
            leaf_order.record(encoder, timer.as_deref_mut());
        }
        if let Some(grids) = &self.rebuilt_grids {
            grids.record(encoder, timer.as_deref_mut());
        }
        let moved = match self.built_for {
            None => true,
            Some(t) => t != time && self.instances.iter().any(|i| i.spin.is_some()),
        };
        if !self.instances.is_empty() && moved {
            self.place_instances(ctx, encoder, timer.as_deref_mut(), time)?;
        }
        if let Some(hardware) = &mut self.hardware {
            let instances = &self.instances;
            hardware.record(encoder, timer, moved, || instances.iter().map(|i| (i.group, i.world_from_group_at(time))).collect());
        }
        self.built_for = Some(time);
        Ok(())
    }

    /// Writes the instances as placed at `time`, and the software top level over them where shading
    /// walks it (the hardware back end builds its own, `HardwareVolumes::record`).
    fn place_instances(
        &mut self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        timer: Option<&mut GpuTimer>,
        time: f32,
    ) -> Result<()> {
        let placed: Vec<(Affine3A, &Group)> = self.instances.iter().map(|i| (i.world_from_group_at(time), &self.groups[i.group])).collect();
        let gpu: Vec<GpuVolumeInstance> = placed.iter().map(|(t, g)| GpuVolumeInstance::new(*t, g)).collect();
        let boxes: Vec<Aabb> = placed.iter().map(|(t, g)| g.bounds.transformed(t)).collect();
        if let Some(i) = boxes.iter().position(|b| !b.is_valid()) {
            return Err(Error::InvalidScene(format!("{} instance {i}: its bounds are not finite at time {time}", self.label)));
        }
        ctx.queue.write_buffer(&self.buffers.instances, 0, bytemuck::cast_slice(&gpu));
        let first = GpuFirstInstance { instance: gpu[0], entry_grid_header: placed[0].1.grid.map_or_else(BvhNode::zeroed, |g| g.node) };
        ctx.queue.write_buffer(&self.buffers.first_instance, 0, bytemuck::bytes_of(&first));
        if self.hardware.is_some() {
            return Ok(());
        }
        match &mut self.top_level_builder {
            Some(builder) => {
                builder.set_boxes(&ctx.queue, &boxes)?;
                builder.record(encoder, timer, TimerSpan::whole(self.top_level_scope))?;
            }
            None => {
                // The top level sits at the start of both arrays, its leaves naming instances.
                let top_level = Bvh::build_with_leaf_size(&boxes, 1)?;
                ctx.queue.write_buffer(&self.buffers.nodes, 0, bytemuck::cast_slice(&top_level.nodes));
                ctx.queue.write_buffer(&self.buffers.primitives, 0, bytemuck::cast_slice(&top_level.primitive_indices));
            }
        }
        Ok(())
    }
}

impl Volumes<'_> {
    /// Checks that there is one record per box and that every box is finite.
    fn check(&self) -> Result<()> {
        let label = self.kind.label();
        let count = self.boxes.len();
        if self.items.len() != count * self.kind.record_bytes() {
            return Err(Error::InvalidConfig(format!(
                "{} bytes of {label} records for {count} volumes; each record takes {} bytes",
                self.items.len(),
                self.kind.record_bytes()
            )));
        }
        if let Some(i) = self.boxes.iter().position(|b| !b.is_valid()) {
            return Err(Error::InvalidScene(format!("{label} {i}: its volume has a NaN, infinite or inverted bound {:?}", self.boxes[i])));
        }
        Ok(())
    }
}

/// Where a structure's groups and instances lie in its arrays: the top level's nodes first (one
/// instance per leaf), then every group's grid header node and BVH (at most 2n − 1 nodes), then the
/// dynamic group's; primitives are the top level's instance indices, then every item, then the CPU
/// builds' grids and lists.
struct Layout {
    /// Volumes, without the dynamic group's.
    count: usize,
    ranges: Vec<Range<usize>>,
    /// Instances of non-empty groups (instances of empty groups can contain nothing), then the
    /// dynamic group's, at identity.
    instances: Vec<GroupInstance>,
    dynamic: Option<DynamicGroup>,
    instance_slots: u32,
    /// Each group's root node.
    group_roots: Vec<u32>,
    dynamic_root: u32,
    node_count: u32,
}

impl Layout {
    fn new(volumes: &Volumes) -> Self {
        let count = volumes.boxes.len();
        let (ranges, all_instances) = volumes.groups.resolve(count);
        let mut instances: Vec<GroupInstance> = all_instances.into_iter().filter(|i| !ranges[i.group].is_empty()).collect();
        let dynamic = volumes.dynamic.filter(|d| d.count > 0);
        if dynamic.is_some() {
            instances.push(GroupInstance { group: ranges.len(), world_from_group: Affine3A::IDENTITY, spin: None });
        }
        let instance_slots = instances.len().max(1) as u32;
        let mut node_base = 2 * instance_slots - 1;
        let mut group_roots = Vec::with_capacity(ranges.len());
        for range in &ranges {
            group_roots.push(node_base + 1);
            node_base += 1 + (2 * range.len() as u32).saturating_sub(1);
        }
        let dynamic_root = node_base + 1;
        node_base += 1 + (2 * dynamic.map_or(0, |d| d.count)).saturating_sub(1);
        Self { count, ranges, instances, dynamic, instance_slots, group_roots, dynamic_root, node_count: node_base }
    }

    fn dynamic_count(&self) -> u32 {
        self.dynamic.map_or(0, |d| d.count)
    }

    fn top_level_nodes(&self) -> u32 {
        2 * self.instance_slots - 1
    }

    /// Primitive indices: the top level's, then every item's, the dynamic group's too.
    fn primitive_count(&self) -> u64 {
        u64::from(self.instance_slots) + self.count as u64 + u64::from(self.dynamic_count())
    }
}

/// A group built once on the CPU: its BVH, and what its queries read before it, if anything.
struct CpuGroup {
    bvh: Bvh,
    grid: Option<GroupGrid>,
}

/// Each group's CPU build where `build` asks for one, but for the `listed` group's, whose lists built
/// on the GPU replace its BVH: its BVH (with wide leaves where `volumes.wide_leaves` asks), and its
/// entry grid or, for crowded decals that are one group placed once, its cell lists where they fit
/// ([`VolumeStructure::cell_lists`]). Only the placed group gets lists: groups without an instance
/// are never queried. Grids share one budget of cells and cover words for all the groups
/// (`GridBudget`), lists one of list words (`cell_lists::MAX_LIST_WORDS`).
fn cpu_builds(volumes: &Volumes, layout: &Layout, build: GroupBuild, listed: Option<usize>) -> Result<Vec<Option<CpuGroup>>> {
    const _: () = assert!(DECAL_LAYERS - 1 <= cell_lists::MAX_RANK);
    let tree = if volumes.wide_leaves { Bvh::build_wide } else { Bvh::build };
    let trees = layout
        .ranges
        .iter()
        .enumerate()
        .map(|(group, range)| {
            (build == GroupBuild::CpuOnce && !range.is_empty() && listed != Some(group))
                .then(|| tree(&volumes.boxes[range.clone()]))
                .transpose()
        })
        .collect::<Result<Vec<_>>>()?;
    let wide_leaves = volumes.wide_leaves && trees.iter().any(Option::is_some);
    let listed_group = (volumes.kind == VolumeKind::Decals
        && volumes.cell_lists == GroupLists::BesideBvh
        && wide_leaves
        && layout.instances.len() == 1
        && layout.dynamic.is_none())
    .then(|| layout.instances[0].group);
    let grid_budget = entry_grid::GridBudget::for_structure(layout.count);
    let list_words_per_primitive = cell_lists::MAX_LIST_WORDS as f64 / layout.count.max(1) as f64;
    let groups = trees.into_iter().zip(&layout.ranges).enumerate().map(|(group, (tree, range))| {
        tree.map(|bvh| {
            let lists = (listed_group == Some(group))
                .then(|| decal_cell_lists_in_leaf_order(volumes, range, &bvh, (range.len() as f64 * list_words_per_primitive) as usize))
                .flatten();
            let grid = match lists {
                Some(lists) => Some(GroupGrid::Lists(lists)),
                None => EntryGrid::build(&bvh, &volumes.boxes[range.clone()], grid_budget).map(GroupGrid::Entry),
            };
            CpuGroup { bvh, grid }
        })
    });
    Ok(groups.collect())
}

/// The cell lists of the decal group over `range`, its items in `bvh`'s leaf order, as stored.
fn decal_cell_lists_in_leaf_order(volumes: &Volumes, range: &Range<usize>, bvh: &Bvh, budget_words: usize) -> Option<CellLists> {
    let record_bytes = std::mem::size_of::<GpuDecal>();
    let (boxes, records): (Vec<Aabb>, Vec<GpuDecal>) = bvh
        .primitive_indices
        .iter()
        .map(|&p| {
            let item = range.start + p as usize;
            let record: GpuDecal = bytemuck::pod_read_unaligned(&volumes.items[item * record_bytes..(item + 1) * record_bytes]);
            (volumes.boxes[item], record)
        })
        .unzip();
    decal_cell_lists(&boxes, &records, budget_words)
}

/// Each item's scene index, in the order the items are stored: a CPU-built group's in its leaf
/// order; the others' as the scene has them until their builds sort them.
fn stored_order(ranges: &[Range<usize>], cpu_groups: &[Option<CpuGroup>]) -> Vec<u32> {
    ranges
        .iter()
        .zip(cpu_groups)
        .flat_map(|(range, group)| {
            let start = range.start as u32;
            match group {
                Some(group) => group.bvh.primitive_indices.iter().map(|&p| start + p).collect::<Vec<_>>(),
                None => range.clone().map(|i| i as u32).collect(),
            }
        })
        .collect()
}

/// A structure's GPU arrays.
struct Buffers {
    items: wgpu::Buffer,
    nodes: wgpu::Buffer,
    primitives: wgpu::Buffer,
    instances: wgpu::Buffer,
    /// A [`GpuFirstInstance`].
    first_instance: wgpu::Buffer,
    /// Each node's [`LightTreeNode`] where light groups have their tree, else one placeholder.
    light_tree: wgpu::Buffer,
    builds_light_tree: bool,
}

impl Buffers {
    fn new(ctx: &GpuContext, volumes: &Volumes, layout: &Layout, node_bytes: u64, primitive_bytes: u64) -> Self {
        use wgpu::BufferUsages as U;
        let label = volumes.kind.label();
        let buffer = |name: &str, size: u64, usage| {
            ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(&format!("{label} {name}")),
                size: size.max(4),
                usage,
                mapped_at_creation: false,
            })
        };
        let item_bytes = volumes.items.len() as u64 + u64::from(layout.dynamic_count()) * volumes.kind.record_bytes() as u64;
        let instance_bytes = u64::from(layout.instance_slots) * std::mem::size_of::<GpuVolumeInstance>() as u64;
        // The order of creation decides where the driver places the arrays, which measurably moves
        // shading's speed (benchmarks/LOG.md, topic 1): the items come last.
        let nodes = buffer("bvh nodes", node_bytes, U::STORAGE | U::COPY_DST | U::COPY_SRC);
        let primitives = buffer("bvh primitives", primitive_bytes, U::STORAGE | U::COPY_DST | U::COPY_SRC);
        let instances = buffer("instances", instance_bytes, U::STORAGE | U::COPY_DST);
        let first_instance = buffer("first instance", std::mem::size_of::<GpuFirstInstance>() as u64, U::UNIFORM | U::COPY_DST);
        let items = buffer("items", item_bytes.max(64), U::STORAGE | U::COPY_DST);
        let tree_bytes = if volumes.light_tree { node_bytes } else { 0 }.max(std::mem::size_of::<LightTreeNode>() as u64);
        let light_tree = buffer("light tree", tree_bytes, U::STORAGE | U::COPY_DST);
        Self { items, nodes, primitives, instances, first_instance, light_tree, builds_light_tree: volumes.light_tree }
    }

    /// Writes the items in their stored order (`scene_indices`).
    fn write_items_in_order(&self, ctx: &GpuContext, volumes: &Volumes, scene_indices: &[u32]) {
        let bytes = volumes.kind.record_bytes();
        let in_order: Vec<u8> =
            scene_indices.iter().flat_map(|&i| &volumes.items[i as usize * bytes..(i as usize + 1) * bytes]).copied().collect();
        if !in_order.is_empty() {
            ctx.queue.write_buffer(&self.items, 0, &in_order);
        }
    }

    /// Where a GPU build writes a BVH: nodes from `node_base`, primitives from `primitive_base`, its
    /// leaves naming items from `item_base`; with the light tree of its nodes where `group` is a
    /// group's BVH (not the top level) and the structure has one.
    fn target(&self, node_base: u32, primitive_base: u32, item_base: u32, group: bool) -> LbvhTarget {
        LbvhTarget {
            nodes: self.nodes.clone(),
            primitives: self.primitives.clone(),
            node_base,
            primitive_base,
            item_base,
            leaf_base: item_base,
            light_tree: (group && self.builds_light_tree).then(|| self.light_tree.clone()),
        }
    }

    /// The buffers shading binds, in binding order.
    fn bound(&self) -> [&wgpu::Buffer; 6] {
        [&self.items, &self.nodes, &self.primitives, &self.instances, &self.first_instance, &self.light_tree]
    }
}

/// Every group but the dynamic one in the arrays: a CPU-built group's BVH and grid written once, a
/// GPU-rebuilt group's builder set up over its boxes.
fn place_groups(
    ctx: &GpuContext,
    volumes: &Volumes,
    layout: &Layout,
    buffers: &Buffers,
    build: GroupBuild,
    cpu_groups: Vec<Option<CpuGroup>>,
    rebuilds: Vec<Rebuild>,
) -> Result<(Vec<Group>, Vec<RebuiltGroup>)> {
    let node_offset = |node: u32| u64::from(node) * std::mem::size_of::<BvhNode>() as u64;
    let mut next_cell = layout.primitive_count() as u32;
    let mut groups = Vec::with_capacity(layout.ranges.len() + 1);
    let mut rebuilt = Vec::new();
    for (((range, &blas_root), cpu_group), rebuild) in layout.ranges.iter().zip(&layout.group_roots).zip(cpu_groups).zip(rebuilds) {
        let items = range.start as u32..range.end as u32;
        let boxes = &volumes.boxes[range.clone()];
        let bounds = boxes.iter().fold(Aabb::EMPTY, |b, x| b.union(*x));
        let mut grid = None;
        let builder = match cpu_group {
            Some(CpuGroup { bvh, grid: group_grid }) => {
                let nodes = relocate(&bvh, blas_root, items.start);
                ctx.queue.write_buffer(&buffers.nodes, node_offset(blas_root), bytemuck::cast_slice(&nodes));
                if volumes.light_tree {
                    let lights: &[GpuLight] = bytemuck::cast_slice(&volumes.items[group_bytes(volumes, range)]);
                    let tree = light_tree_nodes(&bvh, lights);
                    ctx.queue.write_buffer(&buffers.light_tree, node_offset(blas_root), bytemuck::cast_slice(&tree));
                }
                if let Some(group_grid) = group_grid {
                    let (cells, header) = group_grid.gpu_words(blas_root, items.start, next_cell);
                    ctx.queue.write_buffer(&buffers.primitives, u64::from(next_cell) * 4, bytemuck::cast_slice(&cells));
                    ctx.queue.write_buffer(&buffers.nodes, node_offset(blas_root - 1), bytemuck::bytes_of(&header.node));
                    grid = Some(header);
                    next_cell += cells.len() as u32;
                }
                None
            }
            None if boxes.is_empty() || build == GroupBuild::None => None,
            None => {
                if let Rebuild::Lists(placement) = rebuild {
                    // Rebuilt as cell lists (`RebuiltCellLists`), whose grid its queries read from
                    // its header.
                    grid = Some(GridHeader { node: placement.header(), flag: 0 });
                    groups.push(Group { items, blas_root, grid, dynamic: false, bounds, builder: None, boxes: None });
                    continue;
                }
                let target = buffers.target(blas_root, layout.instance_slots + items.start, items.start, true);
                let leaves = max_leaf_size(volumes.rebuilt_leaves);
                let mut builder = GpuLbvh::with_target(ctx, boxes.len() as u32, target)?.with_max_leaf_size(leaves);
                builder.set_boxes(&ctx.queue, boxes)?;
                if volumes.light_tree {
                    let lights: &[GpuLight] = bytemuck::cast_slice(&volumes.items[group_bytes(volumes, range)]);
                    builder.set_emitters(&ctx.queue, &lights.iter().map(LightTreeNode::of_light).collect::<Vec<_>>())?;
                }
                if let Rebuild::Lbvh(Some(placement)) = rebuild {
                    let node = placement.header(next_cell);
                    ctx.queue.write_buffer(&buffers.nodes, node_offset(blas_root - 1), bytemuck::bytes_of(&node));
                    grid = Some(GridHeader { node, flag: ENTRY_GRID_FLAG });
                    rebuilt.push(RebuiltGroup {
                        placement,
                        first_cell: next_cell,
                        root: blas_root,
                        node_end: blas_root + builder.node_count(),
                    });
                    next_cell += 2 * placement.cells();
                }
                Some(builder)
            }
        };
        groups.push(Group { items, blas_root, grid, dynamic: false, bounds, builder, boxes: None });
    }
    Ok((groups, rebuilt))
}

/// The bytes of `volumes.items` that hold the group over `range`.
fn group_bytes(volumes: &Volumes, range: &Range<usize>) -> Range<usize> {
    let bytes = volumes.kind.record_bytes();
    range.start * bytes..range.end * bytes
}

/// How a group is rebuilt on the GPU every frame, where it is.
#[derive(Clone, Copy, Debug)]
enum Rebuild {
    /// As an LBVH, with the entry grid placed here where `volumes.rebuilt_grids` asks for one.
    Lbvh(Option<GridPlacement>),
    /// As cell lists on this grid, in place of its BVH (`listed`).
    Lists(ListPlacement),
}

/// How each group is rebuilt where `build` rebuilds it: the `listed` group as cell lists, the others
/// as LBVHs.
fn rebuilds(volumes: &Volumes, layout: &Layout, build: GroupBuild, listed: Option<(usize, ListPlacement)>) -> Vec<Rebuild> {
    let gridded = build == GroupBuild::GpuEveryFrame && volumes.rebuilt_grids;
    layout
        .ranges
        .iter()
        .enumerate()
        .map(|(group, range)| match listed {
            Some((listed, placement)) if listed == group => Rebuild::Lists(placement),
            _ => {
                let boxes = &volumes.boxes[range.clone()];
                let bounds = boxes.iter().fold(Aabb::EMPTY, |b, x| b.union(*x));
                Rebuild::Lbvh(gridded.then(|| GridPlacement::for_group(&bounds, boxes.len())).flatten())
            }
        })
        .collect()
}

/// The group built on the GPU as cell lists in place of its BVH (once, or every frame as `build`
/// says), and their grid: the one placed group, where `volumes.cell_lists` asks for them (the plan
/// asks only where nothing else needs the BVH: `plan::lights_listed`, `plan::decals_listed`), no
/// dynamic group joins it, and a grid fits its volumes and the device's bindings
/// (`ListPlacement::for_boxes`); the others keep their BVHs.
fn list_placement(ctx: &GpuContext, volumes: &Volumes, layout: &Layout, build: GroupBuild) -> Option<(usize, ListPlacement)> {
    let GroupLists::InPlaceOfBvh(cells) = volumes.cell_lists else { return None };
    let lone = (layout.instances.len() == 1 && layout.dynamic.is_none()).then(|| layout.instances[0].group)?;
    let boxes = &volumes.boxes[layout.ranges[lone].clone()];
    let every_frame = build == GroupBuild::GpuEveryFrame;
    ListPlacement::for_boxes(boxes, cells.coarsest_edge(), every_frame, ctx.limits.max_storage_buffer_binding_size)
        .map(|placement| (lone, placement))
}

/// The most boxes a leaf of a GPU build holds, as the plan's `leaves` say.
fn max_leaf_size(leaves: DynamicLeaves) -> u32 {
    match leaves {
        DynamicLeaves::Widest => MAX_LEAF_SIZE,
        DynamicLeaves::AtMost(size) => size,
    }
}

/// The dynamic group, after the others: a GPU build over boxes a pass writes every frame.
fn dynamic_group(ctx: &GpuContext, layout: &Layout, buffers: &Buffers, dynamic: DynamicGroup, hardware: bool) -> Result<Group> {
    let first = layout.count as u32;
    let group = Group {
        items: first..first + dynamic.count,
        blas_root: layout.dynamic_root,
        grid: None,
        dynamic: true,
        bounds: dynamic.bounds,
        builder: None,
        boxes: None,
    };
    if hardware {
        // The items in box order: primitive k names item `first + k` (`DynamicTargets`).
        let in_order: Vec<u32> = group.items.clone().collect();
        ctx.queue.write_buffer(&buffers.primitives, u64::from(layout.instance_slots + first) * 4, bytemuck::cast_slice(&in_order));
        let boxes = ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("dynamic group boxes"),
            size: u64::from(dynamic.count) * std::mem::size_of::<[[f32; 4]; 2]>() as u64,
            usage: wgpu::BufferUsages::STORAGE,
            mapped_at_creation: false,
        });
        return Ok(Group { boxes: Some(boxes), ..group });
    }
    let leaf_size = max_leaf_size(dynamic.leaves);
    let target = buffers.target(layout.dynamic_root, layout.instance_slots + first, first, true);
    let mut builder = GpuLbvh::with_target(ctx, dynamic.count, target)?.with_max_leaf_size(leaf_size);
    builder.set_gpu_boxes(&ctx.queue, dynamic.count, &dynamic.bounds)?;
    Ok(Group { builder: Some(builder), ..group })
}

/// The layout of the bind group shading reads. Keep in sync with `shading/light_bindings.wgsl`,
/// `shading/decal_bindings.wgsl` and, with the hardware back end, the `*_ray_query.wgsl` enumerations.
fn shading_bind_group_layout(device: &wgpu::Device, label: &str, hardware: bool) -> wgpu::BindGroupLayout {
    let all = wgpu::ShaderStages::VERTEX_FRAGMENT | wgpu::ShaderStages::COMPUTE;
    let mut entries = [0, 1, 2, 3, 4, 5].map(|binding| bindings::storage_read(binding, all)).to_vec();
    entries.push(bindings::uniform(6, all));
    if layout_has_light_tree(label) {
        entries.push(bindings::storage_read(7, all));
    }
    if hardware {
        entries.push(bindings::acceleration_structure(hardware_binding(label), all));
    }
    bindings::layout(device, label, &entries)
}

/// The binding of the top-level acceleration structure, after the others: 8 for lights, 7 for decals.
fn hardware_binding(label: &str) -> u32 {
    if layout_has_light_tree(label) {
        8
    } else {
        7
    }
}

/// Lights' groups bind their light tree (a placeholder where they have none); decals' have none.
fn layout_has_light_tree(label: &str) -> bool {
    label == VolumeKind::Lights.label()
}

/// The lists' ranges and entries shading binds: the clustered lists', or the rebuilt cell lists'.
fn list_buffers<'a>(clusters: Option<&'a ClusterLists>, rebuilt: Option<&'a RebuiltCellLists>) -> Option<[&'a wgpu::Buffer; 2]> {
    clusters.map(|c| [&c.ranges, &c.entries]).or(rebuilt.map(|l| [&l.ranges, &l.entries]))
}

/// The bind group shading reads (`shading/*_bindings.wgsl`): items, nodes, primitives, instances,
/// the lists' ranges and entries (`list_buffers`, or placeholders without them), and the first
/// instance.
fn shading_bind_group(
    ctx: &GpuContext,
    label: &str,
    layout: &wgpu::BindGroupLayout,
    [items, nodes, primitives, instances, first_instance, light_tree]: [&wgpu::Buffer; 6],
    lists: Option<[&wgpu::Buffer; 2]>,
    hardware: Option<&HardwareVolumes>,
) -> wgpu::BindGroup {
    let placeholder;
    let [ranges, entries] = match lists {
        Some(lists) => lists,
        None => {
            placeholder = ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("no cluster lists"),
                size: 16,
                usage: wgpu::BufferUsages::STORAGE,
                mapped_at_creation: false,
            });
            [&placeholder, &placeholder]
        }
    };
    let mut resources = [items, nodes, primitives, instances, ranges, entries, first_instance].map(|b| b.as_entire_binding()).to_vec();
    if layout_has_light_tree(label) {
        resources.push(light_tree.as_entire_binding());
    }
    if let Some(hardware) = hardware {
        resources.push(hardware.binding());
    }
    bindings::bind_group(&ctx.device, label, layout, resources)
}

/// Moves a CPU-built BVH's nodes into the shared array: node links by `node_base` (the last node's
/// [`END`](super::END) stays, ending the group's traversal), leaf ranges by `item_base`, where the
/// group's items are stored in leaf order.
fn relocate(bvh: &Bvh, node_base: u32, item_base: u32) -> Vec<BvhNode> {
    bvh.nodes.iter().map(|n| n.offset(node_base, item_base)).collect()
}

#[cfg(test)]
mod tests {
    use std::mem::{offset_of, size_of};

    use super::*;
    use crate::accel::END;

    #[test]
    fn volume_instance_matches_its_wgsl_layout() {
        let module = naga::front::wgsl::parse_str(include_str!("bvh_types.wgsl")).unwrap();
        let mut layouter = naga::proc::Layouter::default();
        layouter.update(module.to_ctx()).unwrap();
        let (_, ty) = module.types.iter().find(|(_, t)| t.name.as_deref() == Some("VolumeInstance")).unwrap();
        let naga::TypeInner::Struct { members, span } = &ty.inner else { panic!("VolumeInstance is not a struct") };
        assert_eq!(*span as usize, size_of::<GpuVolumeInstance>());
        let wgsl: Vec<(String, u32)> = members.iter().map(|m| (m.name.clone().unwrap(), m.offset)).collect();
        let rust: Vec<(String, u32)> = [
            ("group_from_world", offset_of!(GpuVolumeInstance, group_from_world)),
            ("world_from_group", offset_of!(GpuVolumeInstance, world_from_group)),
            ("first_item", offset_of!(GpuVolumeInstance, first_item)),
            ("item_count", offset_of!(GpuVolumeInstance, item_count)),
            ("blas_root", offset_of!(GpuVolumeInstance, blas_root)),
            ("scale", offset_of!(GpuVolumeInstance, scale)),
        ]
        .into_iter()
        .map(|(n, o)| (n.to_string(), o as u32))
        .collect();
        assert_eq!(wgsl, rust);
    }

    #[test]
    fn instance_rows_map_points_both_ways() {
        let t = Affine3A::from_scale_rotation_translation(
            glam::Vec3::splat(2.0),
            glam::Quat::from_rotation_y(0.5),
            glam::Vec3::new(1.0, 2.0, 3.0),
        );
        let mut group = Group { items: 4..9, blas_root: 17, grid: None, dynamic: false, bounds: Aabb::EMPTY, builder: None, boxes: None };
        let gpu = GpuVolumeInstance::new(t, &group);
        let apply =
            |rows: &[[f32; 4]; 3], p: glam::Vec3| glam::Vec3::from_array(rows.map(|r| glam::Vec4::from_array(r).dot(p.extend(1.0))));
        let p = glam::Vec3::new(0.3, -1.0, 2.0);
        assert!((apply(&gpu.world_from_group, p) - t.transform_point3(p)).length() < 1e-5);
        assert!((apply(&gpu.group_from_world, apply(&gpu.world_from_group, p)) - p).length() < 1e-5);
        assert_eq!((gpu.first_item, gpu.item_count, gpu.blas_root), (4, 5, 17));
        assert!((gpu.scale - 2.0).abs() < 1e-6);
        group.grid = Some(GridHeader { node: BvhNode::zeroed(), flag: ENTRY_GRID_FLAG });
        assert_eq!(GpuVolumeInstance::new(t, &group).blas_root, 17 | ENTRY_GRID_FLAG);
        group.grid = Some(GridHeader { node: BvhNode::zeroed(), flag: 0 });
        assert_eq!(GpuVolumeInstance::new(t, &group).blas_root, 17);
    }

    /// Cell lists pruned by `decal_may_reach` still list every decal holding a point, for small,
    /// thin, tilted and scaled decals far from the origin, points sampled inside them and on their
    /// corners; the test prunes (tilted boxes' corners reach cells their boxes do not); and each
    /// cell's list runs top layer first, by item within a layer, its entries carrying their layers.
    #[test]
    fn decal_cell_lists_keep_every_decal_holding_a_point_top_layer_first() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_pcg::Pcg64::seed_from_u64(11);
        let far = glam::Vec3::new(3000.0, -200.0, 1200.0);
        let decals: Vec<Decal> = (0..600)
            .map(|_| {
                let rotation = glam::Quat::from_euler(
                    glam::EulerRot::XYZ,
                    rng.random::<f32>() * 6.3,
                    rng.random::<f32>() * 6.3,
                    rng.random::<f32>() * 6.3,
                );
                let size = glam::Vec3::new(rng.random_range(0.05..2.0), rng.random_range(0.05..2.0), rng.random_range(0.01..0.5));
                let centre = far + glam::Vec3::new(rng.random(), rng.random(), rng.random()) * 12.0;
                Decal {
                    world_from_decal: Affine3A::from_scale_rotation_translation(size, rotation, centre),
                    material: 0,
                    layer: rng.random_range(0..DECAL_LAYERS),
                    weight: 1.0,
                }
            })
            .collect();
        let boxes: Vec<Aabb> = decals.iter().map(decal_aabb).collect();
        let records: Vec<GpuDecal> = decals.iter().map(|d| GpuDecal::new(d, 0)).collect();
        let pruned = decal_cell_lists(&boxes, &records, 1 << 22).unwrap();
        let unpruned = CellLists::build(&boxes, &|_, _| true, 1 << 22).unwrap();
        assert_eq!(pruned.dims, unpruned.dims);
        assert!(pruned.items.len() < unpruned.items.len() * 9 / 10, "{} of {} entries", pruned.items.len(), unpruned.items.len());
        for (i, decal) in decals.iter().enumerate() {
            let corners = (0..8).map(|c| glam::Vec3::new((c & 1) as f32, (c >> 1 & 1) as f32, (c >> 2) as f32) - 0.5);
            let inside = (0..20).map(|_| glam::Vec3::new(rng.random(), rng.random(), rng.random()) - 0.5);
            for local in corners.chain(inside) {
                let p = decal.world_from_decal.transform_point3(local);
                if crate::accel::decal_contains(decal, p) {
                    assert!(pruned.list(p).contains(&(i as u32)), "decal {i} holds {p} but its cell does not list it");
                }
            }
        }
        let words = pruned.gpu_words(0, 0);
        let lists_at = 2 * (pruned.starts.len() - 1);
        for w in pruned.starts.windows(2) {
            let entries = &words[lists_at + w[0] as usize..lists_at + w[1] as usize];
            let listed: Vec<(u32, u32)> =
                entries.iter().map(|&e| (e >> cell_lists::RANK_SHIFT, e & ((1 << cell_lists::RANK_SHIFT) - 1))).collect();
            for &(layer, item) in &listed {
                assert_eq!(layer, decals[item as usize].layer, "entry for decal {item} carries layer {layer}");
            }
            assert!(
                listed.windows(2).all(|p| p[0].0 > p[1].0 || (p[0].0 == p[1].0 && p[0].1 < p[1].1)),
                "list not top layer first: {listed:?}"
            );
        }
    }

    /// The mean count of boxes holding a box's centre, within its own group, over CPU-built groups only,
    /// sampled evenly across them.
    #[test]
    fn relocation_offsets_children_and_leaves() {
        let boxes: Vec<Aabb> = (0..20).map(|i| Aabb::new(glam::Vec3::splat(i as f32), glam::Vec3::splat(i as f32 + 0.5))).collect();
        let bvh = Bvh::build(&boxes).unwrap();
        let nodes = relocate(&bvh, 100, 50);
        for (moved, original) in nodes.iter().zip(&bvh.nodes) {
            if original.is_leaf() {
                assert_eq!(moved.leaf_range(), original.leaf_range().start + 50..original.leaf_range().end + 50);
            } else {
                assert_eq!(moved.entry, original.entry + 100);
            }
            let skip = if original.skip == END { END } else { original.skip + 100 };
            assert_eq!(moved.skip, skip);
        }
        assert_eq!(nodes[0].skip, END, "the root ends the group's traversal");
    }
}
