"""The filter update of the ftfusion filter benchmark (fmu/benches/filter.rs) written with vectorised NumPy, as a FilterPy user
would: same map size (4-DOF peg field, 826,281 cells), particles and iterations; prints
`numpy_updates_per_s = X`. Options: --particles N, --iterations K, --measurements M."""

import argparse
import time

import numpy as np

FORCE = 50.0


def field(x, y, rx, ry):
    """The analytic peg-on-rim field of ftfusion::synthetic (channels fx..tz, depth)."""
    r = np.hypot(x, y)
    on_rim = r > 5e-5
    lever = 0.0039 - 0.45 * r
    safe = np.where(on_rim, r, 1.0)
    tx = np.where(on_rim, FORCE * lever * y / safe, 0.0)
    ty = np.where(on_rim, -FORCE * lever * x / safe, 0.0)
    depth = np.where(on_rim, 0.01, 0.0)
    return np.stack([FORCE * ry, -FORCE * rx, np.full_like(x, FORCE), tx, ty, np.zeros_like(x), depth], axis=-1)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--particles", type=int, default=10_000)
    ap.add_argument("--iterations", type=int, default=20)
    ap.add_argument("--measurements", type=int, default=5)
    a = ap.parse_args()
    deg = np.pi / 180
    xs = np.linspace(-5e-3, 5e-3, 101)
    rs = np.linspace(-2 * deg, 2 * deg, 9)
    mins = np.array([-5e-3, -5e-3, -2 * deg, -2 * deg])
    steps = np.array([1e-4, 1e-4, 0.5 * deg, 0.5 * deg])
    counts = np.array([101, 101, 9, 9])
    X, Y, RX, RY = np.meshgrid(xs, xs, rs, rs, indexing="ij")
    cells = field(X, Y, RX, RY).reshape(-1, 7).astype(np.float32)
    strides = np.array([101 * 81, 81, 9, 1])
    truth = np.array([1.7e-3, -2.3e-3, 0.6 * deg, -1.1 * deg])
    meas = field(*truth).astype(np.float32)
    sig = np.array([0.2, 0.2, 0.2, 0.01, 0.01, 0.01, 5e-4], dtype=np.float32)
    inv_var = 1.0 / sig**2
    rng = np.random.default_rng(1)
    n = a.particles
    pos = (rng.random((n, 4)) * (counts - 1)).astype(np.float32)
    lw = np.full(n, -np.log(n))
    corners = np.array([[(c >> k) & 1 for k in range(4)] for c in range(16)])

    t0 = time.perf_counter()
    for _ in range(a.measurements):
        for _ in range(a.iterations):
            t = np.clip(pos, 0, counts - 1)
            lo = np.minimum(t.astype(np.int64), counts - 2)
            f = t - lo
            base = lo @ strides
            w = np.prod(np.where(corners[None], f[:, None, :], 1 - f[:, None, :]), axis=2)  # n x 16
            idx = base[:, None] + corners @ strides
            pred = np.einsum("nc,nck->nk", w, cells[idx])
            ll = -0.5 * ((meas - pred) ** 2 * inv_var).sum(axis=1)
            lw = lw + ll
            lw -= lw.max()
            wts = np.exp(lw)
            wts /= wts.sum()
            lw = np.log(np.maximum(wts, 1e-300))
            ess = 1.0 / np.sum(wts**2)
            if ess <= n / 2:
                cum = np.cumsum(wts)
                u = (rng.random() + np.arange(n)) / n
                pick = np.minimum(np.searchsorted(cum, u), n - 1)
                pos = pos[pick]
                lw = np.full(n, -np.log(n))
            pos = np.clip(pos + 0.2 * rng.standard_normal(pos.shape).astype(np.float32), 0, counts - 1)
    dt = time.perf_counter() - t0
    est = (np.exp(lw)[:, None] * pos).sum(axis=0) * steps + mins
    print(f"numpy_updates_per_s = {n * a.iterations * a.measurements / dt:.3e}")
    print(f"numpy_ms_per_measurement = {1e3 * dt / a.measurements:.2f}")
    print(f"numpy_error_mm = {(est[0] - truth[0]) * 1e3:.3f} {(est[1] - truth[1]) * 1e3:.3f}")


if __name__ == "__main__":
    main()
