// The benchmark's floor: a plain per-pixel copy of a region (one u32 per pixel) through the same
// kind of compute dispatch and storage buffers as the enhancement.

@compute @workgroup_size(TILE, TILE)
fn copy_pixels(@builtin(global_invocation_id) id: vec3<u32>) {
    if (id.x >= pc.region_size.x || id.y >= pc.region_size.y) {
        return;
    }
    let i = id.y * pc.region_size.x + id.x;
    pixels[i] = source[i];
}
