//! The GPU LBVH builder produces valid BVHs (every node box holds its children, every volume in
//! exactly one leaf) whose point queries equal brute force, for degenerate and large inputs; the GPU's
//! rebuilt cell lists list every volume reaching each point's cell, and grow when they must.

use glam::{UVec3, Vec3};
use manylights::{
    accel::{lbvh::GpuLbvh, Aabb, MAX_LEAF_SIZE},
    gpu::GpuContext,
    plan::ListCells,
};
use rand::{Rng, SeedableRng};

fn random_boxes(count: usize, rng: &mut rand_pcg::Pcg64) -> Vec<Aabb> {
    (0..count)
        .map(|i| {
            let centre = Vec3::new(rng.random_range(-50.0..50.0), rng.random_range(-50.0..50.0), rng.random_range(-50.0..50.0));
            let mut half = Vec3::new(rng.random_range(0.0..3.0), rng.random_range(0.0..3.0), rng.random_range(0.0..3.0));
            if i % 5 == 0 {
                half.y = 0.0; // flat
            }
            Aabb::new(centre - half, centre + half)
        })
        .collect()
}

fn build(ctx: &GpuContext, lbvh: &mut GpuLbvh, boxes: &[Aabb]) -> manylights::accel::Bvh {
    lbvh.set_boxes(&ctx.queue, boxes).unwrap();
    let mut encoder = ctx.device.create_command_encoder(&Default::default());
    lbvh.record(&mut encoder, None, manylights::accel::lbvh::TimerSpan::whole("lbvh_build")).unwrap();
    ctx.queue.submit([encoder.finish()]);
    lbvh.read_back(ctx).unwrap()
}

fn check(bvh: &manylights::accel::Bvh, boxes: &[Aabb], rng: &mut rand_pcg::Pcg64) {
    bvh.validate(boxes).unwrap_or_else(|e| panic!("{} boxes: invalid GPU BVH: {e}", boxes.len()));
    // Valid means every box holds its children; the LBVH's boxes are also exact unions (a looser box
    // would only slow queries down, which no other test would notice).
    for (n, node) in bvh.nodes.iter().enumerate() {
        let tight = match bvh.children(node) {
            Some((a, b)) => bvh.nodes[a as usize].bounds().union(bvh.nodes[b as usize].bounds()),
            None => node.leaf_range().map(|slot| boxes[bvh.primitive_indices[slot] as usize]).fold(Aabb::EMPTY, Aabb::union),
        };
        assert_eq!(node.bounds(), tight, "{} boxes: node {n}'s box is not the union of what it holds", boxes.len());
    }
    for _ in 0..2000 {
        // Half the points on box corners and faces, half anywhere.
        let p = if !boxes.is_empty() && rng.random_bool(0.5) {
            let b = boxes[rng.random_range(0..boxes.len())];
            Vec3::new(if rng.random_bool(0.5) { b.min.x } else { b.max.x }, rng.random_range(b.min.y..=b.max.y), b.min.z)
        } else {
            Vec3::new(rng.random_range(-55.0..55.0), rng.random_range(-55.0..55.0), rng.random_range(-55.0..55.0))
        };
        let mut found = Vec::new();
        bvh.query_point(boxes, p, |i| found.push(i));
        found.sort_unstable();
        let expected: Vec<u32> = (0..boxes.len() as u32).filter(|&i| boxes[i as usize].contains(p)).collect();
        assert_eq!(found, expected, "{} boxes, point {p}", boxes.len());
    }
}

#[test]
fn gpu_builds_are_valid_and_exact() {
    let ctx = GpuContext::new().expect("a GPU adapter");
    let mut lbvh = GpuLbvh::new(&ctx, 20_000).unwrap();
    let mut rng = rand_pcg::Pcg64::seed_from_u64(9);
    // 256 boxes fill one block of the bounds pass exactly; 257 and 513 spill into the next.
    for count in [1, 2, 3, 17, 255, 256, 257, 513, 1000, 20_000] {
        let boxes = random_boxes(count, &mut rng);
        let bvh = build(&ctx, &mut lbvh, &boxes);
        assert_eq!(bvh.nodes.len(), 2 * count - 1);
        check(&bvh, &boxes, &mut rng);
    }
    // Identical boxes: every Morton code equal, the tree splits on position alone.
    let same = vec![Aabb::new(Vec3::splat(1.0), Vec3::splat(2.0)); 4096];
    let bvh = build(&ctx, &mut lbvh, &same);
    check(&bvh, &same, &mut rng);
    // No boxes: nothing to build, no nodes.
    assert!(build(&ctx, &mut lbvh, &[]).nodes.is_empty());
}

/// Leaves of several boxes (the particle lights' groups): small subtrees become leaves over their
/// range of sorted boxes, the walk never enters the nodes below them, and queries stay exact.
#[test]
fn gpu_builds_with_leaves_of_several_boxes_are_valid_and_exact() {
    let ctx = GpuContext::new().expect("a GPU adapter");
    let mut rng = rand_pcg::Pcg64::seed_from_u64(21);
    for size in [2, 8, 16, MAX_LEAF_SIZE] {
        let mut lbvh = GpuLbvh::new(&ctx, 5000).unwrap().with_max_leaf_size(size);
        for count in [1, 2, 9, 300, 5000] {
            let boxes = random_boxes(count, &mut rng);
            let bvh = build(&ctx, &mut lbvh, &boxes);
            check(&bvh, &boxes, &mut rng);
            // Every leaf the walk reaches holds at most `size` boxes, and large trees have leaves
            // holding several.
            let mut reached = Vec::new();
            let mut n = 0u32;
            while n != manylights::accel::END {
                let node = &bvh.nodes[n as usize];
                match bvh.children(node) {
                    Some((first, _)) => n = first,
                    None => {
                        reached.push(node.leaf_range().len());
                        n = node.skip;
                    }
                }
            }
            assert_eq!(reached.iter().sum::<usize>(), count, "leaf size {size}: the leaves hold every box once");
            assert!(reached.iter().all(|&l| (1..=size as usize).contains(&l)), "leaf size {size}: {reached:?}");
            if count >= 300 {
                let most = if size >= 8 { count / 3 } else { count - 1 };
                assert!(reached.len() <= most, "leaf size {size}: {} leaves for {count} boxes", reached.len());
            }
        }
    }
}

#[test]
fn bad_volumes_and_overflow_are_errors() {
    let ctx = GpuContext::new().expect("a GPU adapter");
    let mut lbvh = GpuLbvh::new(&ctx, 4).unwrap();
    let nan = Aabb::new(Vec3::new(f32::NAN, 0.0, 0.0), Vec3::ONE);
    assert!(lbvh.set_boxes(&ctx.queue, &[nan]).is_err());
    let unit = Aabb::new(Vec3::ZERO, Vec3::ONE);
    assert!(lbvh.set_boxes(&ctx.queue, &[unit; 5]).is_err());
}

/// With a light tree, every node the walk reaches also gets the emitters below it: the box of its
/// lights' positions and their largest range exactly, their summed power to rounding — across the
/// bounds pass's blocks of 256 leaves and past 256 blocks, where the blocks' prefix sums take
/// several per thread — and lights of no power weigh nothing.
#[test]
fn gpu_builds_give_every_node_the_emitters_below_it() {
    use manylights::accel::light_tree::{union, LightTreeNode, EMPTY};
    let ctx = GpuContext::new().expect("a GPU adapter");
    let mut rng = rand_pcg::Pcg64::seed_from_u64(33);
    for size in [1, 8] {
        let mut lbvh = GpuLbvh::with_light_tree(&ctx, 70_000).unwrap().with_max_leaf_size(size);
        for count in [1, 2, 255, 257, 3000, 70_000] {
            let boxes = random_boxes(count, &mut rng);
            // Each light off its box's centre, with powers over four decades; every tenth dark.
            let emitters: Vec<LightTreeNode> = boxes
                .iter()
                .enumerate()
                .map(|(i, b)| {
                    let p = b.min + (b.max - b.min) * rng.random::<f32>();
                    let power = if i % 10 == 3 { 0.0 } else { 10f32.powf(rng.random_range(-2.0..2.0)) };
                    LightTreeNode { min: p.into(), power, max: p.into(), range: rng.random_range(0.1..4.0) }
                })
                .collect();
            lbvh.set_boxes(&ctx.queue, &boxes).unwrap();
            lbvh.set_emitters(&ctx.queue, &emitters).unwrap();
            let mut encoder = ctx.device.create_command_encoder(&Default::default());
            lbvh.record(&mut encoder, None, manylights::accel::lbvh::TimerSpan::whole("lbvh_build")).unwrap();
            ctx.queue.submit([encoder.finish()]);
            let primitives = lbvh.read_back(&ctx).unwrap().primitive_indices;
            let (nodes, tree) = lbvh.read_back_light_tree(&ctx).unwrap();
            // The emitters below each reached node, gathered by walking down from the root, with
            // the power summed in f64.
            fn below(
                n: u32,
                nodes: &[manylights::accel::BvhNode],
                leaf_emitters: &dyn Fn(usize) -> (LightTreeNode, f64),
            ) -> (LightTreeNode, f64) {
                let node = nodes[n as usize];
                if node.is_leaf() {
                    return node.leaf_range().map(leaf_emitters).fold((EMPTY, 0.0), |(t, p), (e, q)| (union(t, e), p + q));
                }
                let (a, pa) = below(node.entry, nodes, leaf_emitters);
                let (b, pb) = below(nodes[node.entry as usize].skip, nodes, leaf_emitters);
                (union(a, b), pa + pb)
            }
            let leaf_emitters = |slot: usize| {
                let e = emitters[primitives[slot] as usize];
                (e, f64::from(e.power))
            };
            let mut stack = vec![0u32];
            let mut reached = 0;
            while let Some(n) = stack.pop() {
                let (expected, power) = below(n, &nodes, &leaf_emitters);
                let got = tree[n as usize];
                let what = format!("{count} lights, leaves of {size}, node {n}");
                assert_eq!((got.min, got.max, got.range), (expected.min, expected.max, expected.range), "{what}");
                assert!((f64::from(got.power) - power).abs() <= 1e-4 * power + 1e-30, "{what}: power {} against {power}", got.power);
                let node = nodes[n as usize];
                if !node.is_leaf() {
                    stack.extend([node.entry, nodes[node.entry as usize].skip]);
                }
                reached += 1;
            }
            // Leaves of one box: the walk reaches every node.
            if size == 1 {
                assert_eq!(reached, 2 * count - 1);
            } else {
                assert!((1..2 * count).contains(&reached));
            }
        }
    }
    // Emitters are for a tree, one per box.
    let mut plain = GpuLbvh::new(&ctx, 4).unwrap();
    let unit = Aabb::new(Vec3::ZERO, Vec3::ONE);
    plain.set_boxes(&ctx.queue, &[unit; 2]).unwrap();
    assert!(plain.set_emitters(&ctx.queue, &[LightTreeNode::default(); 2]).is_err());
    let mut lbvh = GpuLbvh::with_light_tree(&ctx, 4).unwrap();
    lbvh.set_boxes(&ctx.queue, &[unit; 2]).unwrap();
    assert!(lbvh.set_emitters(&ctx.queue, &[LightTreeNode::default(); 3]).is_err());
}

/// Spheres of every size over a room, the largest visiting hundreds of cells, some of them later
/// moved outside the grid placed for them: each frame's lists name, for a point anywhere, every sphere
/// holding it (exactness), each once, and only spheres reaching its cell. Lists that start with room
/// for a few entries grow, and a frame rendered again then holds them all; the counts the fill passes
/// leave behind start the next frame at zero, so later frames list the same. Lists built once grow
/// and are built again as well.
#[test]
fn rebuilt_cell_lists_list_every_volume_reaching_each_cell() {
    use manylights::accel::rebuilt_cell_lists::{ListBounds, ListPlacement, RebuiltCellLists};
    use manylights::gpu::readback::read_buffer;
    let ctx = GpuContext::new().expect("a GPU adapter");
    let mut rng = rand_pcg::Pcg64::seed_from_u64(41);
    let spheres: Vec<(Vec3, f32)> = (0..3000)
        .map(|i| {
            let centre = Vec3::new(rng.random_range(-15.0..15.0), rng.random_range(0.0..12.0), rng.random_range(-7.0..7.0));
            let radius = if i % 500 == 0 { rng.random_range(2.0..3.0) } else { rng.random_range(0.1..0.3) };
            (centre, radius)
        })
        .collect();
    let aabb = |(c, r): (Vec3, f32)| Aabb::new(c - r, c + r);
    let boxes: Vec<Aabb> = spheres.iter().copied().map(aabb).collect();
    let placement = ListPlacement::for_boxes(&boxes, ListCells::Coarse.coarsest_edge(), true, u64::MAX).unwrap();
    // Moved after placing: some out past the grid's faces, where points outside it still find them.
    let moved: Vec<(Vec3, f32)> =
        spheres.iter().enumerate().map(|(i, &(c, r))| if i % 7 == 0 { (c * Vec3::new(1.3, 1.0, 1.6), r) } else { (c, r) }).collect();
    let bounds: Vec<ListBounds> = moved.iter().map(|&s| ListBounds::of_light(s.0, s.1, aabb(s))).collect();
    let first_item = 5;
    let mut lists = RebuiltCellLists::new(&ctx, "light", "cell_lists_build", placement, &bounds, first_item, 64).unwrap();
    let record = |lists: &mut RebuiltCellLists| {
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        lists.record(&mut encoder, None);
        ctx.queue.submit([encoder.finish()]);
    };
    record(&mut lists);
    assert!(!lists.fitted(&ctx).unwrap(), "64 entries cannot hold the lists");
    assert!(u64::from(lists.capacity()) >= placement.visits / 4, "the lists grew to what the frame needed");
    let mut previous: Option<Vec<Vec<u32>>> = None;
    for frame in 0..2 {
        record(&mut lists);
        assert!(lists.fitted(&ctx).unwrap(), "frame {frame}: the grown lists held every entry");
        let ranges: Vec<[u32; 2]> = read_buffer(&ctx, &lists.ranges).unwrap();
        let entries: Vec<[u32; 2]> = read_buffer(&ctx, &lists.entries).unwrap();
        assert_eq!(ranges.len() as u32, placement.cells());
        let mut total = 0;
        let listed: Vec<Vec<u32>> = ranges
            .iter()
            .map(|&[start, len]| {
                assert_eq!(start, total, "frame {frame}: lists follow each other");
                total += len;
                let mut items: Vec<u32> = entries[start as usize..(start + len) as usize]
                    .iter()
                    .map(|&[instance, item]| {
                        assert_eq!(instance, 0);
                        item - first_item
                    })
                    .collect();
                items.sort_unstable();
                items
            })
            .collect();
        for (cell, items) in listed.iter().enumerate() {
            assert!(items.windows(2).all(|w| w[0] < w[1]), "frame {frame}: cell {cell} lists a volume twice");
            let at = UVec3::new(
                cell as u32 % placement.dims.x,
                (cell as u32 / placement.dims.x) % placement.dims.y,
                cell as u32 / (placement.dims.x * placement.dims.y),
            );
            let corner = placement.min + at.as_vec3() * placement.cell_size;
            // Cells on the grid's faces reach out to infinity; the margin is a thousandth of a cell.
            let low = Vec3::select(at.cmpeq(UVec3::ZERO), Vec3::splat(f32::NEG_INFINITY), corner - placement.cell_size * 2e-3);
            let far = placement.dims - UVec3::ONE;
            let high = Vec3::select(at.cmpeq(far), Vec3::splat(f32::INFINITY), corner + placement.cell_size * 1.002);
            for &item in items {
                let (c, r) = moved[item as usize];
                let gap = (low - c).max(c - high).max(Vec3::ZERO);
                assert!(gap.length() <= r * 1.001, "frame {frame}: cell {cell} lists volume {item}, which does not reach it");
            }
        }
        for k in 0..5000 {
            // Half the points anywhere, half inside a volume (every seventh one moved).
            let p = if k % 2 == 0 {
                Vec3::new(rng.random_range(-25.0..25.0), rng.random_range(-2.0..14.0), rng.random_range(-13.0..13.0))
            } else {
                let (c, r) = moved[7 * rng.random_range(0..moved.len() / 7) + rng.random_range(0..2) * 3];
                c + Vec3::new(rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0)) * r * 0.57
            };
            let c = placement.cell_of(p);
            let cell = ((c.z * placement.dims.y + c.y) * placement.dims.x + c.x) as usize;
            for (item, &(centre, radius)) in moved.iter().enumerate() {
                if centre.distance(p) < radius {
                    assert!(listed[cell].binary_search(&(item as u32)).is_ok(), "frame {frame}: point {p} misses volume {item}");
                }
            }
        }
        if let Some(previous) = &previous {
            assert_eq!(previous, &listed, "the second frame lists the same");
        }
        previous = Some(listed);
    }
    // Built once, lists too short for their first build are built again once grown.
    let mut once = RebuiltCellLists::new(&ctx, "light", "cell_lists_build", placement, &bounds, first_item, 64).unwrap().built_once();
    record(&mut once);
    assert!(!once.fitted(&ctx).unwrap(), "64 entries cannot hold the lists built once");
    record(&mut once);
    assert!(once.fitted(&ctx).unwrap(), "the grown lists built once held every entry");
    let cells = |lists: &RebuiltCellLists| {
        let entries: Vec<[u32; 2]> = read_buffer(&ctx, &lists.entries).unwrap();
        let ranges: Vec<[u32; 2]> = read_buffer(&ctx, &lists.ranges).unwrap();
        let in_cell = |[start, len]: [u32; 2]| {
            let mut items = entries[start as usize..(start + len) as usize].to_vec();
            items.sort_unstable();
            items
        };
        ranges.into_iter().map(in_cell).collect::<Vec<_>>()
    };
    assert!(cells(&once) == cells(&lists), "lists built once are not those rebuilt every frame");
}

/// Oriented boxes (decals) of every size and turn: each frame's lists name, for points inside a box,
/// that box in the points' cell, their oriented test never dropping one.
#[test]
fn rebuilt_cell_lists_list_every_oriented_box_reaching_each_cell() {
    use glam::{Affine3A, Quat};
    use manylights::accel::rebuilt_cell_lists::{ListBounds, ListPlacement, RebuiltCellLists};
    use manylights::gpu::readback::read_buffer;
    let ctx = GpuContext::new().expect("a GPU adapter");
    let mut rng = rand_pcg::Pcg64::seed_from_u64(43);
    let boxes: Vec<Affine3A> = (0..2000)
        .map(|i| {
            let size = if i % 400 == 0 {
                Vec3::new(3.0, 2.0, 0.05)
            } else {
                Vec3::new(rng.random_range(0.2..1.0), rng.random_range(0.2..1.0), 0.1)
            };
            let turn =
                Quat::from_euler(glam::EulerRot::XYZ, rng.random_range(0.0..6.3), rng.random_range(0.0..6.3), rng.random_range(0.0..6.3));
            let centre = Vec3::new(rng.random_range(-15.0..15.0), rng.random_range(0.0..12.0), rng.random_range(-7.0..7.0));
            Affine3A::from_scale_rotation_translation(size, turn, centre)
        })
        .collect();
    let aabb = |world_from_unit: &Affine3A| {
        (0..8).fold(Aabb::EMPTY, |b, k| {
            let corner = Vec3::new((k & 1) as f32, ((k >> 1) & 1) as f32, ((k >> 2) & 1) as f32) - 0.5;
            b.union(Aabb::new(world_from_unit.transform_point3(corner), world_from_unit.transform_point3(corner)))
        })
    };
    let aabbs: Vec<Aabb> = boxes.iter().map(aabb).collect();
    let rows = |world_from_unit: &Affine3A| {
        let unit_from_world = world_from_unit.inverse();
        let m = glam::Mat3::from(unit_from_world.matrix3);
        [0, 1, 2].map(|r| m.row(r).extend(unit_from_world.translation[r]).to_array())
    };
    let bounds: Vec<ListBounds> = boxes.iter().zip(&aabbs).map(|(b, a)| ListBounds::of_decal(a, rows(b))).collect();
    // The finest cells the plan starts from: decals shaded in fragments.
    let placement = ListPlacement::for_boxes(&aabbs, ListCells::Fine.coarsest_edge(), true, u64::MAX).unwrap();
    let mut lists = RebuiltCellLists::new(&ctx, "decal", "cell_lists_build", placement, &bounds, 0, placement.visits as u32).unwrap();
    let mut encoder = ctx.device.create_command_encoder(&Default::default());
    lists.record(&mut encoder, None);
    ctx.queue.submit([encoder.finish()]);
    assert!(lists.fitted(&ctx).unwrap());
    let ranges: Vec<[u32; 2]> = read_buffer(&ctx, &lists.ranges).unwrap();
    let entries: Vec<[u32; 2]> = read_buffer(&ctx, &lists.entries).unwrap();
    let total: u64 = ranges.iter().map(|r| u64::from(r[1])).sum();
    assert!(total < placement.visits, "the oriented test should drop some of the boxes' cells: {total} of {} entries", placement.visits);
    for _ in 0..20_000 {
        let item = rng.random_range(0..boxes.len());
        let unit = Vec3::new(rng.random_range(-0.5..0.5), rng.random_range(-0.5..0.5), rng.random_range(-0.5..0.5));
        let p = boxes[item].transform_point3(unit);
        let c = placement.cell_of(p);
        let [start, len] = ranges[((c.z * placement.dims.y + c.y) * placement.dims.x + c.x) as usize];
        let listed = entries[start as usize..(start + len) as usize].iter().any(|&[_, e]| e == item as u32);
        assert!(listed, "point {p} in box {item} misses it");
    }
}
