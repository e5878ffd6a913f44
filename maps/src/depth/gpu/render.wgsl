// Orthographic z-buffer of a mesh, one draw of 3 x triangles vertices (no vertex buffer).
//
// Each triangle has a 24-float record in `tris`, in window pixel coordinates (pixel (i, j)
// of the window has its centre at (i, j)):
//   0..6   corners of the triangle grown by a small margin (what the rasterizer covers),
//   6..12  the true corners less the anchor, counter-clockwise (positive area),
//   12     height at the anchor, 13..15 height gradient (per pixel in x, y),
//   15..18 per edge (corner k + 1 to k + 2), the least edge function that covers (the
//          CPU's rule: within a thousandth of a pixel outside the edge),
//   18..20 the anchor: the lattice point nearest the first corner,
//   20..24 the pixel box the CPU computes in f64: first and last column, first and last row.
// The fragment shader re-tests coverage of the pixel centre with the CPU's rule against
// the true corners, so the rasterizer's own edge rule never decides coverage.
// The height is written as an R32Float colour (exact), the triangle index + 1 as R32Uint
// (0 = nothing) and the depth buffer (test Greater) only decides visibility: depth is the
// height mapped linearly into [0.25, 0.75], increasing for the top surface and decreasing
// for the bottom one.

struct Tile {
    // Window pixel coordinates of the tile's first pixel.
    origin: vec2<f32>,
    // 2 / tile size: pixel coordinates to normalized device coordinates.
    scale: vec2<f32>,
    // Depth = d0 + (height - hmin) * dscale.
    hmin: f32,
    dscale: f32,
    d0: f32,
    pad: f32,
}

@group(0) @binding(0) var<uniform> tile: Tile;
@group(0) @binding(1) var<storage, read> tris: array<f32>;

struct VertexOut {
    @builtin(position) pos: vec4<f32>,
    @location(0) @interpolate(flat) tri: u32,
}

@vertex
fn vs(@builtin(vertex_index) vi: u32) -> VertexOut {
    let t = vi / 3u;
    let k = vi % 3u;
    let p = vec2<f32>(tris[t * 24u + 2u * k], tris[t * 24u + 2u * k + 1u]) - tile.origin;
    var out: VertexOut;
    // Framebuffer pixel k covers [k, k + 1): its centre k + 0.5 is lattice pixel k.
    out.pos = vec4<f32>((p.x + 0.5) * tile.scale.x - 1.0, 1.0 - (p.y + 0.5) * tile.scale.y, 0.5, 1.0);
    out.tri = t;
    return out;
}

struct FragmentOut {
    @location(0) height: f32,
    @location(1) tri: u32,
    @builtin(frag_depth) depth: f32,
}

// Twice the signed area of (a, b, q).
fn edge(a: vec2<f32>, b: vec2<f32>, q: vec2<f32>) -> f32 {
    return (b.x - a.x) * (q.y - a.y) - (b.y - a.y) * (q.x - a.x);
}

@fragment
fn fs(in: VertexOut) -> FragmentOut {
    let r = in.tri * 24u;
    let pixel = floor(in.pos.xy) + tile.origin;
    if pixel.x < tris[r + 20u] || pixel.x > tris[r + 21u] || pixel.y < tris[r + 22u] || pixel.y > tris[r + 23u] {
        discard;
    }
    // The pixel centre relative to the anchor: whole numbers, exact in f32.
    let q = pixel - vec2<f32>(tris[r + 18u], tris[r + 19u]);
    let c0 = vec2<f32>(tris[r + 6u], tris[r + 7u]);
    let c1 = vec2<f32>(tris[r + 8u], tris[r + 9u]);
    let c2 = vec2<f32>(tris[r + 10u], tris[r + 11u]);
    if edge(c1, c2, q) < tris[r + 15u] || edge(c2, c0, q) < tris[r + 16u] || edge(c0, c1, q) < tris[r + 17u] {
        discard;
    }
    let h = tris[r + 12u] + dot(vec2<f32>(tris[r + 13u], tris[r + 14u]), q);
    var out: FragmentOut;
    out.height = h;
    out.tri = in.tri + 1u;
    out.depth = clamp(tile.d0 + (h - tile.hmin) * tile.dscale, 0.0, 1.0);
    return out;
}
