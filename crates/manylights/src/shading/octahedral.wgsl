// Octahedral encoding of a unit vector into [-1, 1]² (Cigolle et al. 2014): the G-buffer's normals,
// and per-pixel records that keep a normal in a few bits (`octahedral_pack`).

fn octahedral_encode(n: vec3<f32>) -> vec2<f32> {
    let p = n.xy / (abs(n.x) + abs(n.y) + abs(n.z));
    if n.z >= 0.0 {
        return p;
    }
    return (1.0 - abs(p.yx)) * select(vec2<f32>(-1.0), vec2<f32>(1.0), p >= vec2<f32>(0.0));
}

fn octahedral_decode(e: vec2<f32>) -> vec3<f32> {
    var n = vec3<f32>(e, 1.0 - abs(e.x) - abs(e.y));
    let t = saturate(-n.z);
    n = vec3<f32>(n.xy + select(vec2<f32>(t), vec2<f32>(-t), n.xy >= vec2<f32>(0.0)), n.z);
    return normalize(n);
}

// A unit vector in `bits` + `bits` low bits of a word.
fn octahedral_pack(n: vec3<f32>, bits: u32) -> u32 {
    let levels = f32((1u << bits) - 1u);
    let q = vec2<u32>(round(saturate(octahedral_encode(n) * 0.5 + 0.5) * levels));
    return q.x | (q.y << bits);
}

fn octahedral_unpack(packed: u32, bits: u32) -> vec3<f32> {
    let mask = (1u << bits) - 1u;
    let levels = f32(mask);
    return octahedral_decode(vec2<f32>(f32(packed & mask), f32((packed >> bits) & mask)) / levels * 2.0 - 1.0);
}

// A unit vector in 12 + 12 bits with a count of up to 255 in the top 8 (`packed >> 24u`): how
// per-pixel records keep a surface's normal beside the frames or samples behind them.
fn octahedral_pack_counted(n: vec3<f32>, count: u32) -> u32 {
    return octahedral_pack(n, 12u) | (min(count, 255u) << 24u);
}
