// No decals: surfaces keep their own material, the baseline the methods' costs are measured against.
#include "shading/decals.wgsl"

fn apply_decals(s: ShadingInput, dp: PositionGradients) -> ShadingInput {
    return s;
}
