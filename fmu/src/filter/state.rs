//! The filter's state as bytes, for the FMU's saved and serialized states: particles,
//! weights, the random generator, the measurement count and the contacts' TCP poses, so
//! that a restored filter replays bit for bit. The estimate is recomputed on restore.

use rand_xoshiro::Xoshiro256PlusPlus;

use super::{Estimate, Filter};
use crate::error::{FusionError, Result};

/// Appends little-endian values to a byte buffer.
#[derive(Debug, Default)]
pub struct Writer(pub Vec<u8>);

impl Writer {
    /// Appends a u32.
    pub fn u32(&mut self, v: u32) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }

    /// Appends an f64.
    pub fn f64(&mut self, v: f64) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }

    /// Appends a length-prefixed byte string.
    pub fn bytes(&mut self, b: &[u8]) {
        self.u32(b.len() as u32);
        self.0.extend_from_slice(b);
    }

    /// Appends f32 values (no length).
    pub fn f32s(&mut self, v: &[f32]) {
        for x in v {
            self.0.extend_from_slice(&x.to_le_bytes());
        }
    }
}

/// Reads what [`Writer`] wrote, refusing short input.
#[derive(Debug)]
pub struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl<'a> Reader<'a> {
    /// Reads `bytes` from the start.
    pub fn new(bytes: &'a [u8]) -> Self {
        Self { bytes, at: 0 }
    }

    /// The next `len` bytes.
    pub fn take(&mut self, len: usize) -> Result<&'a [u8]> {
        let end = self
            .at
            .checked_add(len)
            .filter(|&e| e <= self.bytes.len())
            .ok_or_else(|| {
                FusionError::State(format!(
                    "truncated: needs {len} bytes at offset {}, has {}",
                    self.at,
                    self.bytes.len()
                ))
            })?;
        let s = &self.bytes[self.at..end];
        self.at = end;
        Ok(s)
    }

    /// The next u32.
    pub fn u32(&mut self) -> Result<u32> {
        let b = self.take(4)?;
        Ok(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    }

    /// The next f64.
    pub fn f64(&mut self) -> Result<f64> {
        let b = self.take(8)?;
        let mut a = [0u8; 8];
        a.copy_from_slice(b);
        Ok(f64::from_le_bytes(a))
    }

    /// The next length-prefixed byte string.
    pub fn bytes(&mut self) -> Result<&'a [u8]> {
        let len = self.u32()? as usize;
        self.take(len)
    }

    /// The next `out.len()` f32 values.
    pub fn f32s(&mut self, out: &mut [f32]) -> Result<()> {
        let b = self.take(out.len() * 4)?;
        for (o, c) in out.iter_mut().zip(b.chunks_exact(4)) {
            *o = f32::from_le_bytes([c[0], c[1], c[2], c[3]]);
        }
        Ok(())
    }

    /// True when everything was read.
    pub fn done(&self) -> bool {
        self.at == self.bytes.len()
    }
}

impl Filter {
    /// Writes the filter's dynamic state (with a fingerprint of its map and size).
    pub fn save(&self, w: &mut Writer) {
        w.u32(self.cfg.particles as u32);
        w.u32(self.lookup.ndim() as u32);
        for a in self.lookup.axes() {
            w.u32(a.count as u32);
            w.f64(a.min);
            w.f64(a.step);
        }
        w.f32s(&self.pos);
        w.f32s(&self.lw);
        w.u32(self.measurements);
        w.f64(self.lost_evidence);
        w.u32(self.presses.len() as u32);
        for p in &self.presses {
            p.iter().for_each(|v| w.f64(*v));
        }
        // Serializing four u64 into JSON cannot fail.
        w.bytes(
            serde_json::to_string(&self.rng)
                .unwrap_or_default()
                .as_bytes(),
        );
    }

    /// Restores what [`Filter::save`] wrote; refuses a state of another map or particle
    /// count and leaves the filter unchanged then.
    pub fn restore(&mut self, r: &mut Reader<'_>) -> Result<()> {
        let n = r.u32()? as usize;
        let d = r.u32()? as usize;
        if n != self.cfg.particles || d != self.lookup.ndim() {
            return Err(FusionError::State(format!(
                "saved with {n} particles over {d} DOFs, this instance has {} over {}",
                self.cfg.particles,
                self.lookup.ndim()
            )));
        }
        for a in self.lookup.axes() {
            let (count, min, step) = (r.u32()? as usize, r.f64()?, r.f64()?);
            if count != a.count || min != a.min || step != a.step {
                return Err(FusionError::State(format!(
                    "saved over another map (axis {} differs)",
                    a.dof
                )));
            }
        }
        let mut pos = vec![0.0; n * d];
        let mut lw = vec![0.0; n];
        r.f32s(&mut pos)?;
        r.f32s(&mut lw)?;
        let measurements = r.u32()?;
        let lost_evidence = r.f64()?;
        if !(lost_evidence.is_finite() && lost_evidence >= 0.0) {
            return Err(FusionError::State(format!(
                "the evidence that the particles are lost is {lost_evidence} nats, not finite and >= 0"
            )));
        }
        let count = r.u32()?;
        if count > measurements {
            return Err(FusionError::State(format!(
                "{count} contact poses for {measurements} measurements"
            )));
        }
        // Grown as read: a corrupt count fails at the bytes' end, not at allocation.
        let mut presses = Vec::new();
        for _ in 0..count {
            let mut p = [0.0; 6];
            for v in &mut p {
                *v = r.f64()?;
            }
            if let Some(v) = p.iter().find(|v| !v.is_finite()) {
                return Err(FusionError::State(format!(
                    "a contact's TCP pose holds {v}"
                )));
            }
            presses.push(p);
        }
        let rng: Xoshiro256PlusPlus = serde_json::from_slice(r.bytes()?)
            .map_err(|e| FusionError::State(format!("random generator state: {e}")))?;
        // Particles live in Omega: coordinates within its bounds (grid units) per axis.
        for (k, a) in self.lookup.axes().iter().enumerate() {
            if let Some(v) = pos[k * n..(k + 1) * n].iter().find(|v| !a.in_omega(**v)) {
                return Err(FusionError::State(format!(
                    "a particle's {} coordinate is {v} grid steps, outside Omega",
                    a.dof
                )));
            }
        }
        // Normalised log-weights are <= 0 (to f32 rounding), -inf for a particle without
        // weight, and at least one is finite.
        if let Some(v) = lw.iter().find(|v| v.is_nan() || **v > 1e-3) {
            return Err(FusionError::State(format!(
                "a particle's log-weight is {v}: the weights are not normalised"
            )));
        }
        if lw.iter().all(|v| v.is_infinite()) {
            return Err(FusionError::State("no particle has weight".into()));
        }
        self.pos = pos;
        self.lw = lw;
        self.measurements = measurements;
        self.lost_evidence = lost_evidence;
        self.presses = presses;
        self.rng = rng;
        self.estimate = Estimate::compute(&self.lookup, &self.cfg, &self.pos, &self.lw);
        Ok(())
    }
}
