// Shifted-difference contact reduction, one workgroup per shift of B against A (the GPU
// twin of `summarize` in cpu.rs).
//
// Each invocation owns whole rows of A (rows t, t + WG, ...), scanned column by column.
// Pass 1: the minimal gap a - b over the pixels where A and the shifted B both have a
// surface (workgroup atomicMin on an order-preserving u32 image of the f32), keeping each
// row's minimum. Pass 2, over the rows whose minimum is a contact: over the contact pixels
// (gap <= min + tol) the count, the sums of column, row, A height and B normal (f32,
// tree-reduced), and per A row the first and last contact column (the caller zeroes
// `rows`).
// Empty pixels arrive as sentinels (A: 1e30, B: -1e30): WGSL has no infinities.
//
// Output per shift s: head[11 s ..] = ordered gap (0xffffffff: no overlap), count,
// f32 bits of sum col, sum row, sum height, sum normal (3), first row with a contact r0,
// last + 1 r1, and where its rows start in `dense`. Per A row r (scratch, zeroed by the
// caller): rows[2 ha s + 2 r] = !first (0: no contact in row r), rows[2 ha s + 2 r + 1] =
// last + 1; the rows r0..r1 of it are then copied to `dense` at a place taken from
// `taken`, so that the caller reads them in one piece.

struct Params {
    wa: u32,
    ha: u32,
    wb: u32,
    hb: u32,
    // Shifts in this dispatch.
    count: u32,
    // Workgroups along x of the dispatch.
    nx: u32,
    // Entries (triples) in `normals`.
    n_normals: u32,
    tol: f32,
}

@group(0) @binding(0) var<uniform> P: Params;
@group(0) @binding(1) var<storage, read> a_h: array<f32>;
// Per A row: first and last column with a surface (first > last when none).
@group(0) @binding(2) var<storage, read> a_span: array<vec2<i32>>;
@group(0) @binding(3) var<storage, read> b_h: array<f32>;
@group(0) @binding(4) var<storage, read> b_tri: array<u32>;
@group(0) @binding(5) var<storage, read> normals: array<f32>;
// Per shift: B column and row of A's pixel (0, 0).
@group(0) @binding(6) var<storage, read> offs: array<vec2<i32>>;
@group(0) @binding(7) var<storage, read_write> head: array<u32>;
@group(0) @binding(8) var<storage, read_write> rows: array<u32>;
@group(0) @binding(9) var<storage, read_write> dense: array<u32>;
// Words of `dense` taken so far (the caller zeroes it).
@group(0) @binding(10) var<storage, read_write> taken: array<atomic<u32>>;

const WG: u32 = 64u;
const ROW_MINS: u32 = 32u;
const A_EMPTY: f32 = 1e29;
const B_EMPTY: f32 = -1e29;
const NONE: u32 = 0xffffffffu;

var<workgroup> wg_min: atomic<u32>;
var<workgroup> wg_gap: u32;
var<workgroup> wg_count: atomic<u32>;
var<workgroup> wg_row_lo: atomic<u32>;
var<workgroup> wg_row_hi: atomic<u32>;
var<workgroup> wg_base: u32;
var<workgroup> red_pos: array<vec3<f32>, WG>;
var<workgroup> red_nrm: array<vec3<f32>, WG>;

// Order-preserving map of f32 onto u32.
fn ordered(x: f32) -> u32 {
    let b = bitcast<u32>(x);
    return select(b | 0x80000000u, ~b, (b & 0x80000000u) != 0u);
}

fn unordered(u: u32) -> f32 {
    return bitcast<f32>(select(~u, u & 0x7fffffffu, (u & 0x80000000u) != 0u));
}

@compute @workgroup_size(WG)
fn main(@builtin(workgroup_id) wid: vec3<u32>, @builtin(local_invocation_index) t: u32) {
    let s = wid.y * P.nx + wid.x;
    if s >= P.count {
        return;
    }
    if t == 0u {
        atomicStore(&wg_min, NONE);
        atomicStore(&wg_count, 0u);
        atomicStore(&wg_row_lo, NONE);
        atomicStore(&wg_row_hi, 0u);
    }
    workgroupBarrier();

    // Rows and columns of A whose shifted pixel lies inside B.
    let off = offs[s];
    let r0 = max(0, -off.y);
    let r1 = min(i32(P.ha), i32(P.hb) - off.y);
    let cb0 = max(0, -off.x);
    let cb1 = min(i32(P.wa), i32(P.wb) - off.x) - 1;

    // Each invocation owns the rows r0 + t + WG k and keeps their minima (the first
    // ROW_MINS of them) to skip rows without contact in pass 2.
    var m = NONE;
    var row_min: array<u32, ROW_MINS>;
    var k = 0u;
    for (var r = r0 + i32(t); r < r1; r += i32(WG)) {
        let span = a_span[r];
        let arow = r * i32(P.wa);
        let brow = (r + off.y) * i32(P.wb) + off.x;
        var rm = NONE;
        for (var c = max(span.x, cb0); c <= min(span.y, cb1); c++) {
            let a = a_h[arow + c];
            let b = b_h[brow + c];
            if a < A_EMPTY && b > B_EMPTY {
                rm = min(rm, ordered(a - b));
            }
        }
        if k < ROW_MINS {
            row_min[k] = rm;
        }
        k++;
        m = min(m, rm);
    }
    atomicMin(&wg_min, m);
    workgroupBarrier();
    if t == 0u {
        wg_gap = atomicLoad(&wg_min);
    }
    let gap = workgroupUniformLoad(&wg_gap);
    let out = s * 11u;
    if gap == NONE {
        if t < 11u {
            head[out + t] = select(0u, NONE, t == 0u);
        }
        return;
    }

    let thr = unordered(gap) + P.tol;
    let thr_ordered = ordered(thr);
    var cnt = 0u;
    var pos = vec3<f32>(0.0);
    var nrm = vec3<f32>(0.0);
    var row_lo = NONE;
    var row_hi = 0u;
    let rbase = s * 2u * P.ha;
    k = 0u;
    for (var r = r0 + i32(t); r < r1; r += i32(WG)) {
        let skip = k < ROW_MINS && row_min[k] > thr_ordered;
        k++;
        if skip {
            continue;
        }
        let span = a_span[r];
        let arow = r * i32(P.wa);
        let brow = (r + off.y) * i32(P.wb) + off.x;
        var first = NONE;
        var last = 0u;
        for (var c = max(span.x, cb0); c <= min(span.y, cb1); c++) {
            let a = a_h[arow + c];
            let b = b_h[brow + c];
            if a < A_EMPTY && b > B_EMPTY && a - b <= thr {
                cnt += 1u;
                pos += vec3<f32>(f32(c), f32(r), a);
                let tri = b_tri[brow + c];
                if tri < P.n_normals {
                    nrm += vec3<f32>(normals[3u * tri], normals[3u * tri + 1u], normals[3u * tri + 2u]);
                }
                first = min(first, u32(c));
                last = u32(c) + 1u;
            }
        }
        if last != 0u {
            rows[rbase + 2u * u32(r)] = ~first;
            rows[rbase + 2u * u32(r) + 1u] = last;
            row_lo = min(row_lo, u32(r));
            row_hi = u32(r) + 1u;
        }
    }
    atomicAdd(&wg_count, cnt);
    atomicMin(&wg_row_lo, row_lo);
    atomicMax(&wg_row_hi, row_hi);
    red_pos[t] = pos;
    red_nrm[t] = nrm;
    workgroupBarrier();
    for (var k = WG / 2u; k > 0u; k >>= 1u) {
        if t < k {
            red_pos[t] += red_pos[t + k];
            red_nrm[t] += red_nrm[t + k];
        }
        workgroupBarrier();
    }
    // Every row of this shift written (storage, this workgroup): the contact rows are
    // copied in one piece to a place of `dense` of their own.
    storageBarrier();
    // The minimum's row is a contact row, so first < last; kept safe anyway.
    let first = atomicLoad(&wg_row_lo);
    let last = max(atomicLoad(&wg_row_hi), first);
    if t == 0u {
        let base = atomicAdd(&taken[0], 2u * (last - first));
        wg_base = base;
        head[out + 8u] = first;
        head[out + 9u] = last;
        head[out + 10u] = base;
        head[out] = gap;
        head[out + 1u] = atomicLoad(&wg_count);
        head[out + 2u] = bitcast<u32>(red_pos[0].x);
        head[out + 3u] = bitcast<u32>(red_pos[0].y);
        head[out + 4u] = bitcast<u32>(red_pos[0].z);
        head[out + 5u] = bitcast<u32>(red_nrm[0].x);
        head[out + 6u] = bitcast<u32>(red_nrm[0].y);
        head[out + 7u] = bitcast<u32>(red_nrm[0].z);
    }
    let base = workgroupUniformLoad(&wg_base);
    for (var i = t; i < 2u * (last - first); i += WG) {
        dense[base + i] = rows[rbase + 2u * first + i];
    }
}
