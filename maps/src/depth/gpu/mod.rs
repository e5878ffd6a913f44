//! The wgpu depth backend (Vulkan only; Mesa's lavapipe when no GPU is present): a render
//! pipeline with a depth buffer for the orthographic z-buffer images and a compute shader
//! for the shifted-difference contact reduction, both equal to [`crate::depth::cpu`] up to the
//! documented rounding.
//!
//! Coverage: the rasterizer covers each triangle grown by [`GROW_PX`] pixel and the
//! fragment shader re-tests the pixel centre against the true triangle with the CPU's rule
//! ([`crate::depth::edge_thresholds`]: covered within [`crate::depth::ON_EDGE_PX`] of it,
//! within the pixel box the CPU computes in f64), in f32 relative to a lattice point by the
//! triangle (the CPU tests in f64). Results differ only for pixel centres whose distance
//! outside an edge is within f32 rounding of that tolerance, and in the triangle index
//! where a pixel centre lies on an edge shared by two triangles of equal height (the
//! height is the same).
//! Heights are written as an R32Float colour (the depth buffer only decides visibility),
//! so they agree with the CPU to f32 rounding (~1e-9 m for parts of centimetres).

use std::collections::HashMap;
use std::sync::{Arc, Mutex, PoisonError, mpsc};

use crate::depth::edge_function as edge;
use crate::depth::{
    ContactSummary, DepthBackend, DepthImage, EDGE_ON, RenderJob, Shift, Surface, edge_thresholds,
    outline_coverage, pixel_box,
};
use crate::error::{MapError, Result};

/// How far (pixels) each triangle is grown for the rasterizer, more than its sub-pixel snapping.
pub const GROW_PX: f64 = 1.0 / 32.0;
/// Floats per triangle record of the render shader.
const TRI_FLOATS: usize = 24;
/// Largest render tile side (pixels); larger windows are rendered in tiles.
const MAX_TILE: u32 = 4096;
/// Upload value of an empty A pixel (the shader's sentinel; WGSL has no infinities).
const A_SENTINEL: f32 = 1e30;
/// Upload value of an empty B pixel.
const B_SENTINEL: f32 = -1e30;
/// Words of a shift's head in the contact shader's output: ordered gap, count, sums of
/// column, row, height and normal (3), first contact row, last + 1, and where its rows
/// start among the contact rows read back.
const HEAD_WORDS: usize = 11;
/// Largest output buffer of one contact dispatch batch (bytes).
const MAX_BATCH_BYTES: u64 = 64 << 20;

/// The wgpu backend: a Vulkan device and its two pipelines.
#[derive(Debug)]
pub struct GpuBackend {
    device: wgpu::Device,
    queue: wgpu::Queue,
    info: wgpu::AdapterInfo,
    limits: wgpu::Limits,
    render_layout: wgpu::BindGroupLayout,
    render_pipeline: wgpu::RenderPipeline,
    contact_layout: wgpu::BindGroupLayout,
    contact_pipeline: wgpu::ComputePipeline,
    /// Errors wgpu reported outside an error scope (it would panic without a handler).
    uncaptured: Arc<Mutex<Option<String>>>,
    /// One GPU operation at a time: error scopes are per device, and the queue is one.
    serial: Mutex<()>,
    /// Buffers kept between operations by role, so that a map's thousands of renders and
    /// reductions reuse device and read-back memory rather than allocate it each time.
    pool: Mutex<HashMap<&'static str, wgpu::Buffer>>,
}

fn gpu_err(context: &str, e: impl std::fmt::Display) -> MapError {
    MapError::Gpu(format!("{context}: {e}"))
}

impl GpuBackend {
    /// Opens the first high-performance Vulkan adapter (a GPU, or lavapipe without one).
    pub fn new() -> Result<Self> {
        pollster::block_on(Self::open())
    }

    /// Like [`GpuBackend::new`], but fails when the adapter is a CPU (lavapipe): for runs
    /// that asked for a real GPU, where a missing vendor Vulkan driver falls back silently.
    pub fn new_require_gpu() -> Result<Self> {
        let backend = Self::new()?;
        if backend.is_cpu_adapter() {
            return Err(MapError::Gpu(format!(
                "a GPU was required but the only Vulkan adapter is `{}` (a CPU rasterizer): install the GPU's Vulkan driver (ICD)",
                backend.info.name
            )));
        }
        Ok(backend)
    }

    /// True when the adapter is a software rasterizer (device type Cpu, e.g. llvmpipe).
    pub fn is_cpu_adapter(&self) -> bool {
        self.info.device_type == wgpu::DeviceType::Cpu
    }

    async fn open() -> Result<Self> {
        let instance = wgpu::Instance::new(wgpu::InstanceDescriptor {
            backends: wgpu::Backends::VULKAN,
            ..wgpu::InstanceDescriptor::new_without_display_handle()
        });
        let adapter = instance
            .request_adapter(&wgpu::RequestAdapterOptions {
                power_preference: wgpu::PowerPreference::HighPerformance,
                ..Default::default()
            })
            .await
            .map_err(|e| {
                MapError::Gpu(format!(
                    "no Vulkan adapter: install mesa-vulkan-drivers and libvulkan1 (lavapipe) or the GPU's Vulkan driver ({e})"
                ))
            })?;
        let info = adapter.get_info();
        let limits = adapter.limits();
        let (device, queue) = adapter
            .request_device(&wgpu::DeviceDescriptor {
                label: Some("ftmap"),
                required_limits: limits.clone(),
                ..Default::default()
            })
            .await
            .map_err(|e| gpu_err(&format!("opening device on `{}`", info.name), e))?;
        let uncaptured = Arc::new(Mutex::new(None));
        let sink = Arc::clone(&uncaptured);
        device.on_uncaptured_error(Arc::new(move |e: wgpu::Error| {
            sink.lock()
                .unwrap_or_else(PoisonError::into_inner)
                .get_or_insert(e.to_string());
        }));
        let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
        let (render_layout, render_pipeline) = render_pipeline(&device);
        let (contact_layout, contact_pipeline) = contact_pipeline(&device);
        if let Some(e) = scope.pop().await {
            return Err(gpu_err("building the pipelines", e));
        }
        Ok(Self {
            device,
            queue,
            info,
            limits,
            render_layout,
            render_pipeline,
            contact_layout,
            contact_pipeline,
            uncaptured,
            serial: Mutex::new(()),
            pool: Mutex::new(HashMap::new()),
        })
    }

    /// Runs one GPU operation alone, turning every wgpu error it raises into [`MapError::Gpu`].
    fn guarded<T>(&self, what: &str, op: impl FnOnce() -> Result<T>) -> Result<T> {
        let _serial = self.serial.lock().unwrap_or_else(PoisonError::into_inner);
        let validation = self.device.push_error_scope(wgpu::ErrorFilter::Validation);
        let memory = self.device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
        let internal = self.device.push_error_scope(wgpu::ErrorFilter::Internal);
        let out = op();
        let errors = [internal.pop(), memory.pop(), validation.pop()].map(pollster::block_on);
        let error = errors.into_iter().flatten().next().map(|e| e.to_string());
        let uncaptured = self
            .uncaptured
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .take();
        let out = match error.or(uncaptured) {
            Some(e) => Err(gpu_err(what, e)),
            None => out.map_err(|e| match e {
                MapError::Gpu(m) => MapError::Gpu(format!("{what}: {m}")),
                other => other,
            }),
        };
        if out.is_err() {
            // A failed operation may leave a pooled buffer mapped or half written.
            self.pool
                .lock()
                .unwrap_or_else(PoisonError::into_inner)
                .clear();
        }
        out
    }

    /// The pooled buffer of role `label` with at least `size` bytes (16 at least: wgpu
    /// refuses empty bindings); a larger one (to the next power of two or MiB) replaces a
    /// smaller.
    fn pooled(&self, label: &'static str, size: u64, usage: wgpu::BufferUsages) -> wgpu::Buffer {
        let size = size.max(16).next_multiple_of(wgpu::COPY_BUFFER_ALIGNMENT);
        let mut pool = self.pool.lock().unwrap_or_else(PoisonError::into_inner);
        match pool.get(label) {
            Some(b) if b.size() >= size && b.usage() == usage => b.clone(),
            _ => {
                let b = self.device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some(label),
                    size: size.next_power_of_two().min(size.next_multiple_of(1 << 20)),
                    usage,
                    mapped_at_creation: false,
                });
                pool.insert(label, b.clone());
                b
            }
        }
    }

    /// The pooled buffer of role `label` holding `data` from its start, written through the
    /// queue (so before the next submission's commands run).
    fn upload(&self, label: &'static str, data: &[u8], usage: wgpu::BufferUsages) -> wgpu::Buffer {
        let buffer = self.pooled(
            label,
            data.len() as u64,
            usage | wgpu::BufferUsages::COPY_DST,
        );
        let whole = data.len() - data.len() % 4;
        if whole > 0 {
            self.queue.write_buffer(&buffer, 0, &data[..whole]);
        }
        if whole < data.len() {
            let mut tail = [0u8; 4];
            tail[..data.len() - whole].copy_from_slice(&data[whole..]);
            self.queue.write_buffer(&buffer, whole as u64, &tail);
        }
        buffer
    }

    fn check_binding(&self, what: &str, bytes: u64) -> Result<()> {
        let max = self
            .limits
            .max_storage_buffer_binding_size
            .min(self.limits.max_buffer_size);
        if bytes > max {
            return Err(MapError::Gpu(format!(
                "{what} needs {bytes} bytes, more than the adapter's {max}-byte storage binding limit"
            )));
        }
        Ok(())
    }

    /// Submits `encoder`, waits, and passes `read` the first `len` bytes of each (MAP_READ)
    /// buffer of `buffers`, read in place.
    fn finish_and_read<T>(
        &self,
        encoder: wgpu::CommandEncoder,
        buffers: &[(&wgpu::Buffer, u64)],
        read: impl FnOnce(&[&[u8]]) -> T,
    ) -> Result<T> {
        self.queue.submit([encoder.finish()]);
        let (tx, rx) = mpsc::channel();
        for (k, (b, len)) in buffers.iter().enumerate() {
            let tx = tx.clone();
            b.map_async(wgpu::MapMode::Read, ..*len, move |r| {
                // The receiver outlives the poll below; a failed send cannot happen.
                let _ = tx.send((k, r));
            });
        }
        drop(tx);
        self.device
            .poll(wgpu::PollType::wait_indefinitely())
            .map_err(|e| gpu_err("waiting for the device", e))?;
        let mut mapped = 0;
        for (k, r) in rx.try_iter() {
            r.map_err(|e| gpu_err(&format!("mapping read-back buffer {k}"), e))?;
            mapped += 1;
        }
        if mapped != buffers.len() {
            return Err(MapError::Gpu(format!(
                "only {mapped} of {} read-back buffers were mapped",
                buffers.len()
            )));
        }
        let views = buffers
            .iter()
            .map(|(b, len)| {
                b.get_mapped_range(..*len)
                    .map_err(|e| gpu_err("reading a mapped buffer", e))
            })
            .collect::<Result<Vec<_>>>()?;
        let out = read(&views.iter().map(|v| &v[..]).collect::<Vec<_>>());
        drop(views);
        for (b, _) in buffers {
            b.unmap();
        }
        Ok(out)
    }

    /// Draws `job`'s triangle `records` (heights `hmin..hmax`) into `img`, tile by tile.
    fn draw(
        &self,
        job: &RenderJob<'_>,
        (records, hmin, hmax): &(Vec<[f32; TRI_FLOATS]>, f64, f64),
        img: &mut DepthImage,
    ) -> Result<()> {
        let win = job.window;
        let bytes: &[u8] = bytemuck::cast_slice(records);
        self.check_binding("the triangle records", bytes.len() as u64)?;
        let vertices = u32::try_from(job.mesh.faces.len() * 3).map_err(|_| {
            MapError::Gpu(format!(
                "{} triangles are too many for one draw",
                job.mesh.faces.len()
            ))
        })?;
        let tris = self.upload("triangles", bytes, wgpu::BufferUsages::STORAGE);
        let (hmin, hmax) = (*hmin, *hmax);
        let half_range = if hmax > hmin {
            0.5 / (hmax - hmin)
        } else {
            0.0
        };
        let (d0, dscale) = match job.surface {
            Surface::Top => (0.25, half_range),
            Surface::Bottom => (0.75, -half_range),
        };
        let side = self.limits.max_texture_dimension_2d.min(MAX_TILE) as usize;
        for ty in (0..win.height).step_by(side) {
            for tx in (0..win.width).step_by(side) {
                let (tw, th) = (side.min(win.width - tx), side.min(win.height - ty));
                let tile = [
                    tx as f32,
                    ty as f32,
                    2.0 / tw as f32,
                    2.0 / th as f32,
                    hmin as f32,
                    dscale as f32,
                    d0,
                    0.0,
                ];
                let tris = (&tris, bytes.len() as u64);
                self.render_tile(tris, vertices, &tile, (tx, ty, tw, th), img)?;
            }
        }
        Ok(())
    }

    /// Renders the tile (x, y, width, height) of the window into `img`.
    fn render_tile(
        &self,
        (tris, tri_bytes): (&wgpu::Buffer, u64),
        vertices: u32,
        tile: &[f32; 8],
        (tx, ty, tw, th): (usize, usize, usize, usize),
        img: &mut DepthImage,
    ) -> Result<()> {
        let size = wgpu::Extent3d {
            width: tw as u32,
            height: th as u32,
            depth_or_array_layers: 1,
        };
        let target = |label, format, usage| {
            self.device.create_texture(&wgpu::TextureDescriptor {
                label: Some(label),
                size,
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format,
                usage,
                view_formats: &[],
            })
        };
        let color = wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC;
        let height = target("height", wgpu::TextureFormat::R32Float, color);
        let tri = target("triangle", wgpu::TextureFormat::R32Uint, color);
        let depth = target(
            "depth",
            wgpu::TextureFormat::Depth32Float,
            wgpu::TextureUsages::RENDER_ATTACHMENT,
        );
        let uniform = self.upload(
            "tile",
            bytemuck::cast_slice(tile),
            wgpu::BufferUsages::UNIFORM,
        );
        let bind = self.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("render"),
            layout: &self.render_layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: uniform.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: bytes_of(tris, tri_bytes),
                },
            ],
        });
        let row_bytes = (tw as u32 * 4).next_multiple_of(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT);
        let read_bytes = u64::from(row_bytes) * th as u64;
        let readback = |label| {
            self.pooled(
                label,
                read_bytes,
                wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
            )
        };
        let (height_out, tri_out) = (readback("height read-back"), readback("triangle read-back"));
        let mut encoder = self
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("render"),
            });
        {
            let [hv, tv, dv] = [&height, &tri, &depth]
                .map(|t| t.create_view(&wgpu::TextureViewDescriptor::default()));
            let clear = |view| {
                Some(wgpu::RenderPassColorAttachment {
                    view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                        store: wgpu::StoreOp::Store,
                    },
                })
            };
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("z-buffer"),
                color_attachments: &[clear(&hv), clear(&tv)],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &dv,
                    depth_ops: Some(wgpu::Operations {
                        load: wgpu::LoadOp::Clear(0.0),
                        store: wgpu::StoreOp::Discard,
                    }),
                    stencil_ops: None,
                }),
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_pipeline(&self.render_pipeline);
            pass.set_bind_group(0, &bind, &[]);
            pass.draw(0..vertices, 0..1);
        }
        for (texture, buffer) in [(&height, &height_out), (&tri, &tri_out)] {
            encoder.copy_texture_to_buffer(
                texture.as_image_copy(),
                wgpu::TexelCopyBufferInfo {
                    buffer,
                    layout: wgpu::TexelCopyBufferLayout {
                        offset: 0,
                        bytes_per_row: Some(row_bytes),
                        rows_per_image: None,
                    },
                },
                size,
            );
        }
        let read = [(&height_out, read_bytes), (&tri_out, read_bytes)];
        self.finish_and_read(encoder, &read, |out| {
            let (heights, tris): (&[f32], &[u32]) =
                (bytemuck::cast_slice(out[0]), bytemuck::cast_slice(out[1]));
            let (row_words, width) = (row_bytes as usize / 4, img.window.width);
            for r in 0..th {
                for c in 0..tw {
                    let (src, dst) = (r * row_words + c, (ty + r) * width + tx + c);
                    // Pixels without a fragment keep the image's empty value.
                    if let Some(t) = tris[src].checked_sub(1) {
                        img.height[dst] = heights[src];
                        img.tri[dst] = t;
                    }
                }
            }
        })
    }

    /// The contact shader's output for every shift of B against A, per batch of shifts:
    /// their heads and their contact rows, copied out of the read-back buffers ([`decode`]).
    fn reduce(
        &self,
        a: &DepthImage,
        b: &DepthImage,
        b_normals: &[[f32; 3]],
        shifts: &[Shift],
        tolerance: f32,
    ) -> Result<Vec<(Vec<u32>, Vec<u32>)>> {
        for (name, img) in [("A", a), ("B", b)] {
            if img.height.len() != img.window.len() || img.tri.len() != img.window.len() {
                return Err(MapError::Geometry(format!(
                    "depth image {name} has {} heights for a {}x{} window",
                    img.height.len(),
                    img.window.width,
                    img.window.height
                )));
            }
        }
        let dims = [
            a.window.width,
            a.window.height,
            b.window.width,
            b.window.height,
        ];
        if dims.iter().any(|&d| d > (i32::MAX as usize) / 2)
            || a.window.len() > i32::MAX as usize
            || b.window.len() > i32::MAX as usize
        {
            return Err(MapError::Gpu(format!(
                "depth images of {dims:?} pixels are too large for the contact shader"
            )));
        }
        let ha = a.window.height;
        let encode = |img: &DepthImage, sentinel: f32| -> Vec<f32> {
            img.height
                .iter()
                .map(|&h| if h.is_finite() { h } else { sentinel })
                .collect()
        };
        let spans: Vec<[i32; 2]> = a
            .height
            .chunks_exact(a.window.width)
            .map(|row| {
                match (
                    row.iter().position(|h| h.is_finite()),
                    row.iter().rposition(|h| h.is_finite()),
                ) {
                    (Some(f), Some(l)) => [f as i32, l as i32],
                    _ => [0, -1],
                }
            })
            .collect();
        let a_h = encode(a, A_SENTINEL);
        let b_h = encode(b, B_SENTINEL);
        for (what, bytes) in [
            ("depth image A", a_h.len() * 4),
            ("depth image B", b_h.len() * 4),
            ("B's normals", b_normals.len() * 12),
        ] {
            self.check_binding(what, bytes as u64)?;
        }
        let storage = wgpu::BufferUsages::STORAGE;
        let inputs = [
            self.upload("A heights", bytemuck::cast_slice(&a_h), storage),
            self.upload("A row spans", bytemuck::cast_slice(&spans), storage),
            self.upload("B heights", bytemuck::cast_slice(&b_h), storage),
            self.upload("B triangles", bytemuck::cast_slice(&b.tri), storage),
            self.upload("B normals", bytemuck::cast_slice(b_normals), storage),
        ];

        // Batches: outputs within the binding limit, workgroups within the dispatch limit.
        let per_shift = 4 * (HEAD_WORDS as u64 + 2 * ha as u64);
        let max_bytes = self
            .limits
            .max_storage_buffer_binding_size
            .min(self.limits.max_buffer_size)
            .min(MAX_BATCH_BYTES);
        self.check_binding("the per-row contact output of one shift", per_shift)?;
        let max_dim = u64::from(self.limits.max_compute_workgroups_per_dimension);
        let batch = (max_bytes / per_shift)
            .min(max_dim * max_dim)
            .min(shifts.len() as u64)
            .max(1) as usize;
        let out_usage = wgpu::BufferUsages::STORAGE
            | wgpu::BufferUsages::COPY_SRC
            | wgpu::BufferUsages::COPY_DST;
        let read_usage = wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ;
        let (head_bytes, rows_bytes) = (
            batch as u64 * 4 * HEAD_WORDS as u64,
            batch as u64 * 8 * ha as u64,
        );
        let head = self.pooled("contact heads", head_bytes, out_usage);
        let rows = self.pooled("contact rows", rows_bytes, out_usage);
        let dense = self.pooled("contact rows in one piece", rows_bytes, out_usage);
        let taken = self.pooled("contact rows taken", 4, out_usage);
        let head_read = self.pooled("contact heads read-back", head_bytes, read_usage);
        let taken_read = self.pooled("contact rows taken read-back", 4, read_usage);
        let dense_read = self.pooled("contact rows read-back", rows_bytes, read_usage);

        let mut out = Vec::new();
        for chunk in shifts.chunks(batch) {
            let offs: Vec<[i32; 2]> = chunk
                .iter()
                .map(|s| {
                    let clamp = |v: i64| v.clamp(-(1 << 30), 1 << 30) as i32;
                    [
                        clamp(a.window.i0 - s.du - b.window.i0),
                        clamp(a.window.j0 - s.dv - b.window.j0),
                    ]
                })
                .collect();
            let n = chunk.len() as u32;
            let nx = n.min(self.limits.max_compute_workgroups_per_dimension);
            let params: [u32; 8] = [
                a.window.width as u32,
                ha as u32,
                b.window.width as u32,
                b.window.height as u32,
                n,
                nx,
                b_normals.len() as u32,
                tolerance.to_bits(),
            ];
            let params = self.upload(
                "contact parameters",
                bytemuck::cast_slice(&params),
                wgpu::BufferUsages::UNIFORM,
            );
            let offs = self.upload("shift offsets", bytemuck::cast_slice(&offs), storage);
            let (used_head, used_rows) = (
                u64::from(n) * 4 * HEAD_WORDS as u64,
                u64::from(n) * 8 * ha as u64,
            );
            // Each bound over the bytes it holds: a pooled buffer may be larger.
            let resources = [
                (&params, 32),
                (&inputs[0], a_h.len() as u64 * 4),
                (&inputs[1], spans.len() as u64 * 8),
                (&inputs[2], b_h.len() as u64 * 4),
                (&inputs[3], b.tri.len() as u64 * 4),
                (&inputs[4], b_normals.len() as u64 * 12),
                (&offs, u64::from(n) * 8),
                (&head, used_head),
                (&rows, used_rows),
                (&dense, used_rows),
                (&taken, 4),
            ];
            let entries: Vec<wgpu::BindGroupEntry<'_>> = resources
                .iter()
                .enumerate()
                .map(|(k, (buffer, bytes))| wgpu::BindGroupEntry {
                    binding: k as u32,
                    resource: bytes_of(buffer, *bytes),
                })
                .collect();
            let bind = self.device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("contacts"),
                layout: &self.contact_layout,
                entries: &entries,
            });
            let mut encoder = self
                .device
                .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                    label: Some("contacts"),
                });
            encoder.clear_buffer(&rows, 0, Some(used_rows));
            encoder.clear_buffer(&taken, 0, None);
            {
                let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                    label: Some("contacts"),
                    timestamp_writes: None,
                });
                pass.set_pipeline(&self.contact_pipeline);
                pass.set_bind_group(0, &bind, &[]);
                pass.dispatch_workgroups(nx, n.div_ceil(nx), 1);
            }
            encoder.copy_buffer_to_buffer(&head, 0, &head_read, 0, used_head);
            encoder.copy_buffer_to_buffer(&taken, 0, &taken_read, 0, 4);
            let words = self.finish_and_read(encoder, &[(&taken_read, 4)], |bytes| {
                bytemuck::cast_slice::<u8, u32>(bytes[0])[0]
            })?;
            // Then the contact rows, as much of them as the shifts took (4 bytes at least).
            let used_dense = (4 * u64::from(words)).clamp(4, used_rows);
            let mut encoder = self
                .device
                .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                    label: Some("contact rows"),
                });
            encoder.copy_buffer_to_buffer(&dense, 0, &dense_read, 0, used_dense);
            let read = [(&head_read, used_head), (&dense_read, used_dense)];
            out.push(self.finish_and_read(encoder, &read, |bytes| {
                (
                    bytemuck::cast_slice::<u8, u32>(bytes[0]).to_vec(),
                    bytemuck::cast_slice::<u8, u32>(bytes[1]).to_vec(),
                )
            })?);
        }
        Ok(out)
    }
}

impl DepthBackend for GpuBackend {
    fn name(&self) -> String {
        format!("gpu:{} ({:?})", self.info.name, self.info.device_type)
    }

    fn render(&self, job: &RenderJob<'_>) -> Result<DepthImage> {
        let mut img = DepthImage::empty(job.window, job.pixel, job.surface);
        if job.window.is_empty() || job.mesh.faces.is_empty() {
            return Ok(img);
        }
        // The records and the outline on the CPU, outside the GPU's turn.
        let records = triangle_records(job);
        self.guarded("rendering a depth image", || {
            self.draw(job, &records, &mut img)
        })?;
        outline_coverage(job, &mut img);
        Ok(img)
    }

    fn contacts(
        &self,
        a: &DepthImage,
        b: &DepthImage,
        b_normals: &[[f32; 3]],
        shifts: &[Shift],
        tolerance: f32,
    ) -> Result<Vec<ContactSummary>> {
        let none = ContactSummary::none(f32::INFINITY);
        if shifts.is_empty() || a.window.is_empty() || b.window.is_empty() {
            return Ok(vec![none; shifts.len()]);
        }
        let batches = self.guarded("reducing contacts", || {
            self.reduce(a, b, b_normals, shifts, tolerance)
        })?;
        // Decoded outside the GPU's turn, beside the other threads' use of it: the contact
        // rows come in one piece, so that copying them out is short.
        Ok(batches
            .iter()
            .flat_map(|(heads, dense)| {
                (heads.chunks_exact(HEAD_WORDS)).map(|head| decode(head, dense, &none))
            })
            .collect())
    }
}

/// The first `bytes` of `buffer` as a binding (16 at least, as [`GpuBackend::pooled`]
/// sizes a buffer): a pooled buffer may be larger than what it holds.
fn bytes_of(buffer: &wgpu::Buffer, bytes: u64) -> wgpu::BindingResource<'_> {
    wgpu::BindingResource::Buffer(wgpu::BufferBinding {
        buffer,
        offset: 0,
        size: std::num::NonZeroU64::new(bytes.max(16).next_multiple_of(4)),
    })
}

/// The summary of one shift from its [`HEAD_WORDS`] head words and the contact rows of
/// every shift, `dense`, of which it reads its own: 2 words per row from its first contact
/// row to its last, from where the head says.
fn decode(head: &[u32], dense: &[u32], none: &ContactSummary) -> ContactSummary {
    if head[0] == u32::MAX {
        return none.clone();
    }
    let (first, base) = (head[8] as usize, head[10] as usize);
    let count = (head[9] as usize).saturating_sub(first);
    let rows = dense.get(base..base + 2 * count).unwrap_or(&[]);
    let f = |k: usize| f64::from(f32::from_bits(head[k]));
    ContactSummary {
        gap: from_ordered(head[0]),
        count: head[1],
        sum_col: f(2),
        sum_row: f(3),
        sum_height: f(4),
        sum_normal: [f(5), f(6), f(7)],
        rows: (rows.chunks_exact(2).enumerate())
            .filter(|(_, fl)| fl[0] != 0)
            .map(|(k, fl)| ((first + k) as u32, !fl[0], fl[1] - 1))
            .collect(),
        deficit: 0.0,
    }
}

/// Order-preserving map of an f32 onto a u32 (the shader's `ordered`).
#[cfg(test)]
fn to_ordered(x: f32) -> u32 {
    let b = x.to_bits();
    if b & 0x8000_0000 != 0 {
        !b
    } else {
        b | 0x8000_0000
    }
}

/// Inverse of the shader's order-preserving f32 -> u32 map.
fn from_ordered(u: u32) -> f32 {
    f32::from_bits(if u & 0x8000_0000 != 0 {
        u & 0x7fff_ffff
    } else {
        !u
    })
}

/// The render shader's per-triangle records (window pixel coordinates) and the height range.
fn triangle_records(job: &RenderJob<'_>) -> (Vec<[f32; TRI_FLOATS]>, f64, f64) {
    let (mut hmin, mut hmax) = (f64::INFINITY, f64::NEG_INFINITY);
    let records = (0..job.mesh.faces.len())
        .map(|t| {
            let mut p = job.corners(t);
            let mut area = edge(p[0], p[1], p[2]);
            let pixels = pixel_box(&p, job.window.width, job.window.height);
            let Some(pixels) = pixels.filter(|_| area.abs() >= EDGE_ON) else {
                // Edge-on or outside the window, as on the CPU: no fragments.
                return [0.0; TRI_FLOATS];
            };
            if area < 0.0 {
                p.swap(1, 2);
                area = -area;
            }
            for q in &p {
                hmin = hmin.min(q[2]);
                hmax = hmax.max(q[2]);
            }
            let (d1, d2) = (
                [p[1][0] - p[0][0], p[1][1] - p[0][1], p[1][2] - p[0][2]],
                [p[2][0] - p[0][0], p[2][1] - p[0][1], p[2][2] - p[0][2]],
            );
            let gx = (d1[2] * d2[1] - d2[2] * d1[1]) / area;
            let gy = (d1[0] * d2[2] - d2[0] * d1[2]) / area;
            let grown = grow(&p, area);
            // The corners and the plane are anchored at a lattice point next to the first
            // corner: the shader's q - anchor is then exact, the corners' rounding is
            // relative to the triangle's size, and steep planes keep their precision.
            let anchor = [p[0][0].round(), p[0][1].round()];
            let mut r = [0.0f32; TRI_FLOATS];
            for k in 0..3 {
                r[2 * k] = grown[k][0] as f32;
                r[2 * k + 1] = grown[k][1] as f32;
                r[6 + 2 * k] = (p[k][0] - anchor[0]) as f32;
                r[7 + 2 * k] = (p[k][1] - anchor[1]) as f32;
            }
            for (k, least) in edge_thresholds(&p).into_iter().enumerate() {
                r[15 + k] = least as f32;
            }
            r[12] = (p[0][2] + gx * (anchor[0] - p[0][0]) + gy * (anchor[1] - p[0][1])) as f32;
            r[13] = gx as f32;
            r[14] = gy as f32;
            r[18] = anchor[0] as f32;
            r[19] = anchor[1] as f32;
            for (k, v) in pixels.into_iter().enumerate() {
                r[20 + k] = v as f32;
            }
            r
        })
        .collect();
    (records, hmin, hmax)
}

/// The triangle `p` (counter-clockwise, twice-area `area`) with every edge moved out by
/// [`GROW_PX`]: scaled about its incentre, or for slivers a triangle around its grown
/// bounding box (a sliver's scaled corners would fly far off).
fn grow(p: &[[f64; 3]; 3], area: f64) -> [[f64; 2]; 3] {
    let len = |a: [f64; 3], b: [f64; 3]| (a[0] - b[0]).hypot(a[1] - b[1]);
    let sides = [len(p[1], p[2]), len(p[2], p[0]), len(p[0], p[1])];
    let perimeter: f64 = sides.iter().sum();
    let inradius = area / perimeter;
    if inradius >= 4.0 * GROW_PX {
        let centre = [0, 1].map(|c| (0..3).map(|k| sides[k] * p[k][c]).sum::<f64>() / perimeter);
        let scale = (inradius + GROW_PX) / inradius;
        return p.map(|q| {
            [
                centre[0] + (q[0] - centre[0]) * scale,
                centre[1] + (q[1] - centre[1]) * scale,
            ]
        });
    }
    let lo = [0, 1].map(|c| p.iter().map(|q| q[c]).fold(f64::INFINITY, f64::min) - GROW_PX);
    let hi = [0, 1].map(|c| p.iter().map(|q| q[c]).fold(f64::NEG_INFINITY, f64::max) + GROW_PX);
    let (w, h) = (hi[0] - lo[0], hi[1] - lo[1]);
    [lo, [lo[0] + 2.5 * w, lo[1]], [lo[0], lo[1] + 2.5 * h]]
}

fn storage_entry(
    binding: u32,
    visibility: wgpu::ShaderStages,
    read_only: bool,
) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only },
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

fn uniform_entry(visibility: wgpu::ShaderStages) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding: 0,
        visibility,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Uniform,
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

fn render_pipeline(device: &wgpu::Device) -> (wgpu::BindGroupLayout, wgpu::RenderPipeline) {
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("render.wgsl"),
        source: wgpu::ShaderSource::Wgsl(include_str!("render.wgsl").into()),
    });
    let both = wgpu::ShaderStages::VERTEX_FRAGMENT;
    let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("render"),
        entries: &[uniform_entry(both), storage_entry(1, both, true)],
    });
    let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some("render"),
        bind_group_layouts: &[Some(&layout)],
        immediate_size: 0,
    });
    let target = |format| {
        Some(wgpu::ColorTargetState {
            format,
            blend: None,
            write_mask: wgpu::ColorWrites::ALL,
        })
    };
    let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some("z-buffer"),
        layout: Some(&pipeline_layout),
        vertex: wgpu::VertexState {
            module: &module,
            entry_point: Some("vs"),
            compilation_options: Default::default(),
            buffers: &[],
        },
        primitive: wgpu::PrimitiveState {
            cull_mode: None,
            ..Default::default()
        },
        depth_stencil: Some(wgpu::DepthStencilState {
            format: wgpu::TextureFormat::Depth32Float,
            depth_write_enabled: Some(true),
            depth_compare: Some(wgpu::CompareFunction::Greater),
            stencil: Default::default(),
            bias: Default::default(),
        }),
        multisample: Default::default(),
        fragment: Some(wgpu::FragmentState {
            module: &module,
            entry_point: Some("fs"),
            compilation_options: Default::default(),
            targets: &[
                target(wgpu::TextureFormat::R32Float),
                target(wgpu::TextureFormat::R32Uint),
            ],
        }),
        multiview_mask: None,
        cache: None,
    });
    (layout, pipeline)
}

fn contact_pipeline(device: &wgpu::Device) -> (wgpu::BindGroupLayout, wgpu::ComputePipeline) {
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("contacts.wgsl"),
        source: wgpu::ShaderSource::Wgsl(include_str!("contacts.wgsl").into()),
    });
    let cs = wgpu::ShaderStages::COMPUTE;
    let mut entries = vec![uniform_entry(cs)];
    entries.extend((1..=6).map(|b| storage_entry(b, cs, true)));
    entries.extend((7..=10).map(|b| storage_entry(b, cs, false)));
    let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("contacts"),
        entries: &entries,
    });
    let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some("contacts"),
        bind_group_layouts: &[Some(&layout)],
        immediate_size: 0,
    });
    let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some("contacts"),
        layout: Some(&pipeline_layout),
        module: &module,
        entry_point: Some("main"),
        compilation_options: Default::default(),
        cache: None,
    });
    (layout, pipeline)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ordered_map_preserves_order_and_round_trips() {
        let xs = [
            f32::NEG_INFINITY,
            -1e30,
            -3.5,
            -1e-7,
            -0.0,
            0.0,
            1e-38,
            2e-7,
            0.25,
            7.0,
            1e30,
            f32::INFINITY,
        ];
        for w in xs.windows(2) {
            assert!(to_ordered(w[0]) <= to_ordered(w[1]), "{} {}", w[0], w[1]);
        }
        for x in xs {
            assert_eq!(from_ordered(to_ordered(x)).to_bits(), x.to_bits());
        }
        assert!(
            to_ordered(f32::INFINITY) < u32::MAX,
            "u32::MAX is the shader's `no overlap`"
        );
    }

    #[test]
    fn grown_triangles_contain_the_original_with_margin() {
        let tris = [
            [[0.0, 0.0, 0.0], [10.0, 0.0, 0.0], [0.0, 10.0, 0.0]],
            [[0.0, 0.0, 0.0], [100.0, 0.01, 0.0], [50.0, 0.02, 0.0]],
        ];
        for p in tris {
            let area = edge(p[0], p[1], p[2]);
            let g = grow(&p, area).map(|q| [q[0], q[1], 0.0]);
            let ga = edge(g[0], g[1], g[2]);
            for q in p {
                for k in 0..3 {
                    let (a, b) = (g[k], g[(k + 1) % 3]);
                    let dist = edge(a, b, q) / len(a, b);
                    assert!(
                        dist * ga.signum() >= GROW_PX * 0.99,
                        "{p:?}: corner {q:?} only {dist} inside"
                    );
                }
            }
        }
        fn len(a: [f64; 3], b: [f64; 3]) -> f64 {
            (a[0] - b[0]).hypot(a[1] - b[1])
        }
    }

    #[test]
    fn decode_reads_rows_and_no_overlap() {
        let none = ContactSummary::none(f32::INFINITY);
        let mut head = [0; HEAD_WORDS];
        head[0] = u32::MAX;
        assert_eq!(decode(&head, &[0; 4], &none), none);
        let head = [
            to_ordered(-0.5),
            3,
            6f32.to_bits(),
            2f32.to_bits(),
            1.5f32.to_bits(),
            0,
            0,
            3f32.to_bits(),
            1,
            3,
            2,
        ];
        // Rows 1 and 2 (row 2 without contact), from word 2 of the contact rows, where
        // another shift's row precedes them and one more follows.
        let s = decode(&head, &[!0, 1, !4, 7, 0, 0, !1, 2], &none);
        assert_eq!(
            (s.gap, s.count, s.sum_col, s.sum_normal[2]),
            (-0.5, 3, 6.0, 3.0)
        );
        assert_eq!(s.rows, vec![(1, 4, 6)]);
    }
}
