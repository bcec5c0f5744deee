// Random numbers for stochastic shading (`restir`, the light tree): a hash to seed from, and a
// sequence of uniform numbers per invocation, which the user seeds by setting `random_state`.

var<private> random_state: u32;

// Wellons's lowbias32 integer hash.
fn random_hash(x: u32) -> u32 {
    var h = x ^ (x >> 16u);
    h *= 0x7feb352du;
    h ^= h >> 15u;
    h *= 0x846ca68bu;
    return h ^ (h >> 16u);
}

// The next number of the sequence, uniform in [0, 1): a PCG step (O'Neill 2014).
fn random_next() -> f32 {
    random_state = random_state * 747796405u + 2891336453u;
    let word = ((random_state >> ((random_state >> 28u) + 4u)) ^ random_state) * 277803737u;
    return f32(((word >> 22u) ^ word) >> 8u) / 16777216.0;
}
