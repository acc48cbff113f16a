// The benchmark's second floor: the plain copy with the enhancement's own memory access shape
// (one invocation per tile row, 16 bytes per load and store; shaders/access_wide.wgsl), so the
// enhancement can also be compared against a copy that uses its wide accesses. 4-byte pixels,
// rows 16-byte aligned.

@compute @workgroup_size(TILE, TILE)
fn copy_rows(@builtin(global_invocation_id) id: vec3<u32>) {
    let x0 = id.x * TILE;
    let y = id.y;
    if (x0 >= pc.region_size.x || y >= pc.region_size.y) {
        return;
    }
    for (var c = 0u; c < TILE / 4u; c++) {
        let x = x0 + c * 4u;
        if (x >= pc.region_size.x) {
            break;
        }
        let w = y * pc.region_size.x + x;
        store_words4(w, load_source4(w), 4u);
    }
}
