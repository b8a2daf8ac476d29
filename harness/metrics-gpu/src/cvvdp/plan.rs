//! The GPU work of ColorVideoVDP for one frame size, display and frame rate: every buffer, uniform
//! and bind group made once ([`Plan::new`]), then one frame recorded after another
//! ([`Plan::record_frame`]) from the same steps (STYLE.md 8).
//!
//! For: laying the model's per-frame work (metric.rs `predict_inner` and `process_frame`) out as
//! compute dispatches. Not for: the constants (`model.rs`), the per-pixel arithmetic (the WGSL
//! passes in `shaders/cvvdp/`), or pooling (the CPU, `mod.rs`).
//!
//! Per frame: the input pass (display model, DKL, temporal filters over the frame ring) writes
//! the planes of level 0 (test and reference per channel: 6 for an image, 8 for a video); each
//! band above the baseband reduces every plane to the next level, expands it back, and runs per
//! channel: contrast and CSF (`channel`), the masker's blur and power (`blur` twice), the masked
//! difference and its pooling (`diff`); the baseband takes its mean background (`base_mean`) and
//! the plain difference (`base_channel`). Each pooling writes one partial sum per 16x16
//! workgroup; the CPU adds them in f64 in workgroup order. A frame whose distortion map is
//! wanted adds `map_band` per band, the reconstruction (`expand` accumulating) and `map_jod`.

use crate::cvvdp::model::{self, Decode, Model, CSF_LUMINANCES};
use crate::cvvdp::CvvdpPipelines;
use crate::error::GpuMetricsError;
use crate::plumbing::{Grid1, Layout};

/// The most temporal filter taps the frame ring holds (layers of one texture array).
pub(crate) const MAX_TAPS: usize = 256;
/// Tile of the 2-D passes.
const TILE: u32 = 16;

/// What a plan is made for; a request with another key makes a new plan.
#[derive(Clone, PartialEq)]
pub(crate) struct PlanKey {
    pub width: u32,
    pub height: u32,
    /// Linear (HDR) frames rather than 8-bit sRGB.
    pub linear: bool,
    /// A video (temporal channels) rather than an image.
    pub video: bool,
    /// Frames per second (bits), pixels per degree (bits), photometry (bits), white (bits).
    pub fps: u32,
    pub ppd: u64,
    pub photometry: [u64; 5],
    pub white: u32,
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct InputParams {
    size: [u32; 4],
    m: [[f32; 4]; 3],
    linear: [f32; 4],
    white: [f32; 4],
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
pub(crate) struct TapsUniform {
    weights: [[f32; 4]; MAX_TAPS],
    layers: [u32; MAX_TAPS],
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Size4 {
    v: [u32; 4],
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct ExpandParams {
    v: [u32; 8],
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct CsfUniform {
    table: [f32; CSF_LUMINANCES],
    axis: [f32; 4],
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct ChannelParams {
    w: u32,
    h: u32,
    gain: f32,
    channel_gain: f32,
    csf: CsfUniform,
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct BlurParams {
    size: [u32; 4],
    kernel: [f32; 16],
    mask: [f32; 4],
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct DiffParams {
    size: [u32; 8],
    xcm: [f32; 4],
    values: [f32; 8],
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct BaseChannelParams {
    size: [u32; 4],
    values: [f32; 4],
    csf: CsfUniform,
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct MapBandParams {
    size: [u32; 4],
    weights: [f32; 4],
    values: [f32; 8],
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct MapJodParams {
    size: [u32; 4],
    values: [f32; 4],
}

/// One dispatch: its pipeline, bindings and workgroups.
struct Step {
    pipeline: wgpu::ComputePipeline,
    bind: wgpu::BindGroup,
    groups: [u32; 2],
}

/// Where one (band, channel) pooling's partials lie in a frame's partials.
pub(crate) struct PartialRegion {
    pub band: usize,
    pub channel: usize,
    pub offset: usize,
    pub count: usize,
    pub pixels: usize,
}

/// The buffers, uniforms and steps of one [`PlanKey`].
pub(crate) struct Plan {
    pub key: PlanKey,
    pub channels: usize,
    pub bands: usize,
    pub taps: usize,
    filters: [Vec<f32>; 4],
    ring: [wgpu::Texture; 2],
    taps_uniform: wgpu::Buffer,
    pub partials: Vec<PartialRegion>,
    /// f32 values of one frame's partials.
    pub frame_partials: usize,
    partials_buffer: wgpu::Buffer,
    map: wgpu::Buffer,
    frame_steps: Vec<Step>,
    map_steps: Vec<Step>,
    // Kept alive for the bind groups.
    _buffers: Vec<wgpu::Buffer>,
    _lut: wgpu::Texture,
}

fn storage(device: &wgpu::Device, label: &str, floats: usize) -> wgpu::Buffer {
    device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size: (floats.max(1) * 4) as u64,
        usage: wgpu::BufferUsages::STORAGE
            | wgpu::BufferUsages::COPY_SRC
            | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    })
}

fn tiles(w: u32, h: u32) -> [u32; 2] {
    [w.div_ceil(TILE), h.div_ceil(TILE)]
}

/// A binding of a whole buffer.
fn whole(b: &wgpu::Buffer) -> wgpu::BindingResource<'_> {
    b.as_entire_binding()
}

impl Plan {
    /// Everything for `key`, with the uniforms of `decode` and the calibration. The loops index
    /// planes, channels and bands as the CPU's do.
    #[allow(clippy::too_many_arguments, clippy::needless_range_loop)]
    pub fn new(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        pipelines: &CvvdpPipelines,
        m: &Model,
        key: PlanKey,
        decode: &Decode,
        ppd: f64,
        fps: f32,
        white: f32,
    ) -> Result<Plan, GpuMetricsError> {
        let (w, h) = (key.width, key.height);
        let limits = device.limits();
        let plane_bytes = w as u64 * h as u64 * 4;
        let max_binding = limits
            .max_storage_buffer_binding_size
            .min(limits.max_buffer_size);
        if plane_bytes > max_binding {
            return Err(GpuMetricsError::Unsupported(format!(
                "ColorVideoVDP at {w}x{h} needs {plane_bytes}-byte planes; the device allows \
                 {max_binding}"
            )));
        }
        if w.max(h) > limits.max_texture_dimension_2d {
            return Err(GpuMetricsError::Unsupported(format!(
                "ColorVideoVDP at {w}x{h} needs {w}x{h} textures; the device allows {}",
                limits.max_texture_dimension_2d
            )));
        }
        let frequencies = model::frequencies(w as usize, h as usize, ppd);
        let bands = frequencies.len();
        let (channels, planes) = if key.video { (4, 8) } else { (3, 6) };
        let filters = if key.video {
            model::filters(fps, &m.p)
        } else {
            [vec![1.0], vec![1.0], vec![1.0], vec![1.0]]
        };
        let taps = filters[0].len();
        if taps > MAX_TAPS || taps as u32 > limits.max_texture_array_layers {
            return Err(GpuMetricsError::Unsupported(format!(
                "ColorVideoVDP at {fps} fps needs {taps} temporal filter taps; the GPU back end \
                 holds at most {}",
                MAX_TAPS.min(limits.max_texture_array_layers as usize)
            )));
        }
        let mut sizes = vec![(w, h)];
        for _ in 1..bands {
            let &(pw, ph) = sizes.last().unwrap_or(&(w, h));
            sizes.push((pw.div_ceil(2), ph.div_ceil(2)));
        }
        let px = |b: usize| sizes[b].0 as usize * sizes[b].1 as usize;

        // Buffers: the levels' planes (8 at level 0 so the input pass always has its outputs),
        // the expanded planes, maskers, a blur temporary, the baseband mean and the map bands.
        let level: Vec<Vec<wgpu::Buffer>> = (0..bands)
            .map(|b| {
                let n = if b == 0 { 8 } else { planes };
                (0..n)
                    .map(|_| storage(device, "cvvdp level", px(b)))
                    .collect()
            })
            .collect();
        let expanded: Vec<wgpu::Buffer> = (0..planes)
            .map(|_| storage(device, "cvvdp expanded", px(0)))
            .collect();
        let mutual: Vec<wgpu::Buffer> = (0..4)
            .map(|_| storage(device, "cvvdp masker", px(0)))
            .collect();
        let tmp = storage(device, "cvvdp blur", px(0));
        let mean = storage(device, "cvvdp baseband mean", 4);
        let maps: Vec<wgpu::Buffer> = (0..bands)
            .map(|b| storage(device, "cvvdp map band", px(b)))
            .collect();
        let mut partials = Vec::new();
        let mut frame_partials = 0;
        for (b, &(bw, bh)) in sizes.iter().enumerate() {
            let [gx, gy] = tiles(bw, bh);
            for c in 0..channels {
                partials.push(PartialRegion {
                    band: b,
                    channel: c,
                    offset: frame_partials,
                    count: (gx * gy) as usize,
                    pixels: px(b),
                });
                frame_partials += (gx * gy) as usize;
            }
        }
        let partials_buffer = storage(device, "cvvdp partials", frame_partials);

        let format = if key.linear {
            wgpu::TextureFormat::Rgba32Float
        } else {
            wgpu::TextureFormat::R32Uint
        };
        let ring = [0, 1].map(|_| {
            device.create_texture(&wgpu::TextureDescriptor {
                label: Some("cvvdp frame ring"),
                size: wgpu::Extent3d {
                    width: w,
                    height: h,
                    depth_or_array_layers: taps as u32,
                },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format,
                usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
                view_formats: &[],
            })
        });
        let ring_views = ring.each_ref().map(|t| {
            t.create_view(&wgpu::TextureViewDescriptor {
                dimension: Some(wgpu::TextureViewDimension::D2Array),
                ..Default::default()
            })
        });

        // Uniforms, all static but the taps (written per frame).
        let p = &m.p;
        let correction = 10.0_f32.powf(p.sensitivity_correction / 20.0);
        let last = m.csf.log_l.len() - 1;
        let axis = [
            m.csf.log_l[0],
            m.csf.log_l[last] - m.csf.log_l[0],
            last as f32,
            correction,
        ];
        let csf_tables: Vec<[[f32; CSF_LUMINANCES]; 4]> =
            frequencies.iter().map(|&f| m.csf.at_frequency(f)).collect();
        let csf = |b: usize, c: usize| CsfUniform {
            table: csf_tables[b][c],
            axis,
        };
        let eps = |q: f32| 0.00001_f32.powf(q);
        let mut layout = Layout::default();
        let input_slot = layout.param(&InputParams {
            size: [w, h, taps as u32, key.video as u32],
            m: decode.dkl.map(|r| [r[0], r[1], r[2], 0.0]),
            linear: decode.linear,
            white: [white, 0.0, 0.0, 0.0],
        });

        struct Pending {
            pipeline: wgpu::ComputePipeline,
            slot: u64,
            slot_size: u64,
            buffers: Vec<usize>,
            groups: [u32; 2],
        }
        // Buffers are referred to by index into one list while the uniforms are laid out.
        let mut all: Vec<wgpu::Buffer> = Vec::new();
        let mut id = |b: &wgpu::Buffer| {
            all.push(b.clone());
            all.len() - 1
        };
        let level_id: Vec<Vec<usize>> = level
            .iter()
            .map(|l| l.iter().map(&mut id).collect())
            .collect();
        let expanded_id: Vec<usize> = expanded.iter().map(&mut id).collect();
        let mutual_id: Vec<usize> = mutual.iter().map(&mut id).collect();
        let tmp_id = id(&tmp);
        let mean_id = id(&mean);
        let maps_id: Vec<usize> = maps.iter().map(&mut id).collect();
        let partials_id = id(&partials_buffer);
        let mut steps: Vec<Pending> = Vec::new();
        let mut map_steps: Vec<Pending> = Vec::new();
        let push = |list: &mut Vec<Pending>,
                    layout: &mut Layout,
                    pipeline: &wgpu::ComputePipeline,
                    params: &[u8],
                    buffers: Vec<usize>,
                    groups: [u32; 2]| {
            let slot = layout.params.len() as u64;
            layout.params.extend_from_slice(params);
            let aligned = (params.len() as u64).div_ceil(256) * 256;
            layout.params.resize((slot + aligned) as usize, 0);
            list.push(Pending {
                pipeline: pipeline.clone(),
                slot,
                slot_size: params.len() as u64,
                buffers,
                groups,
            });
        };
        let base = bands - 1;
        let channel_gains = [1.0_f32, 1.45, 1.0, 1.0];
        let mut partial = partials.iter();
        for b in 0..bands {
            let (bw, bh) = sizes[b];
            let g = &level_id[b];
            if b < base {
                let (nw, nh) = sizes[b + 1];
                for pl in 0..planes {
                    push(
                        &mut steps,
                        &mut layout,
                        &pipelines.reduce,
                        bytemuck::bytes_of(&Size4 { v: [bw, bh, 0, 0] }),
                        vec![g[pl], level_id[b + 1][pl]],
                        tiles(nw, nh),
                    );
                }
                for pl in 0..planes {
                    push(
                        &mut steps,
                        &mut layout,
                        &pipelines.expand,
                        bytemuck::bytes_of(&ExpandParams {
                            v: [nw, nh, bw, bh, 0, 0, 0, 0],
                        }),
                        vec![level_id[b + 1][pl], expanded_id[pl]],
                        tiles(bw, bh),
                    );
                }
                let gain = if b == 0 { 1.0 } else { 2.0 };
                for c in 0..channels {
                    push(
                        &mut steps,
                        &mut layout,
                        &pipelines.channel,
                        bytemuck::bytes_of(&ChannelParams {
                            w: bw,
                            h: bh,
                            gain,
                            channel_gain: channel_gains[c],
                            csf: csf(b, c),
                        }),
                        vec![
                            g[2 * c],
                            g[2 * c + 1],
                            expanded_id[2 * c],
                            expanded_id[2 * c + 1],
                            expanded_id[0],
                            expanded_id[1],
                            mutual_id[c],
                        ],
                        tiles(bw, bh),
                    );
                }
                let blurred = bw as usize > m.blur.len() / 2 && bh as usize > m.blur.len() / 2;
                let (radius, kernel) = if blurred {
                    let mut k = [0.0; 16];
                    k[..m.blur.len()].copy_from_slice(&m.blur);
                    ((m.blur.len() / 2) as u32, k)
                } else {
                    let mut k = [0.0; 16];
                    k[0] = 1.0;
                    (0, k)
                };
                let mask_scale = 10.0_f32.powf(p.mask_c);
                for c in 0..channels {
                    for vertical in [0u32, 1] {
                        let (src, dst) = if vertical == 0 {
                            (mutual_id[c], tmp_id)
                        } else {
                            (tmp_id, mutual_id[c])
                        };
                        push(
                            &mut steps,
                            &mut layout,
                            &pipelines.blur,
                            bytemuck::bytes_of(&BlurParams {
                                size: [bw, bh, radius, vertical],
                                kernel,
                                mask: [mask_scale, p.mask_q[c], eps(p.mask_q[c]), 0.0],
                            }),
                            vec![src, dst],
                            tiles(bw, bh),
                        );
                    }
                }
                let max_d = 10.0_f32.powf(p.d_max);
                for c in 0..channels {
                    let r = partial.next().ok_or_else(internal)?;
                    let [gx, _] = tiles(bw, bh);
                    push(
                        &mut steps,
                        &mut layout,
                        &pipelines.diff,
                        bytemuck::bytes_of(&DiffParams {
                            size: [bw, bh, channels as u32, r.offset as u32, gx, 0, 0, 0],
                            xcm: [0, 1, 2, 3].map(|s| m.xcm[s * 4 + c]),
                            values: [
                                p.mask_p,
                                eps(p.mask_p),
                                max_d,
                                p.beta,
                                eps(p.beta),
                                0.0,
                                0.0,
                                0.0,
                            ],
                        }),
                        vec![
                            g[2 * c],
                            g[2 * c + 1],
                            mutual_id[0],
                            mutual_id[1],
                            mutual_id[2],
                            mutual_id[3],
                            partials_id,
                        ],
                        tiles(bw, bh),
                    );
                }
            } else {
                push(
                    &mut steps,
                    &mut layout,
                    &pipelines.base_mean,
                    bytemuck::bytes_of(&Size4 {
                        v: [bw * bh, 0, 0, 0],
                    }),
                    vec![g[0], g[1], mean_id],
                    [1, 1],
                );
                for c in 0..channels {
                    let r = partial.next().ok_or_else(internal)?;
                    let [gx, _] = tiles(bw, bh);
                    push(
                        &mut steps,
                        &mut layout,
                        &pipelines.base_channel,
                        bytemuck::bytes_of(&BaseChannelParams {
                            size: [bw, bh, r.offset as u32, gx],
                            values: [p.beta, eps(p.beta), 0.0, 0.0],
                            csf: csf(b, c),
                        }),
                        vec![g[2 * c], g[2 * c + 1], mean_id, partials_id],
                        tiles(bw, bh),
                    );
                }
            }
            // The map band of this band (recorded only for frames whose map is wanted).
            let weights = p.channel_weights();
            let integration = if key.video { 1.0 } else { p.image_int };
            let map_weights: [f32; 4] = std::array::from_fn(|c| {
                weights[c] * integration * if b == base { p.baseband_weight[c] } else { 1.0 }
            });
            let gain = if b == 0 || b == base { 1.0 } else { 2.0 };
            let d3 = if channels > 3 { g[6] } else { g[0] };
            push(
                &mut map_steps,
                &mut layout,
                &pipelines.map_band,
                bytemuck::bytes_of(&MapBandParams {
                    size: [bw, bh, channels as u32, 0],
                    weights: map_weights,
                    values: [
                        p.beta_tch,
                        eps(p.beta_tch),
                        1.0 / p.beta_tch,
                        eps(1.0 / p.beta_tch),
                        gain,
                        0.0,
                        0.0,
                        0.0,
                    ],
                }),
                vec![g[0], g[2], g[4], d3, maps_id[b]],
                tiles(bw, bh),
            );
        }
        for b in (0..base).rev() {
            let (bw, bh) = sizes[b];
            let (nw, nh) = sizes[b + 1];
            push(
                &mut map_steps,
                &mut layout,
                &pipelines.expand,
                bytemuck::bytes_of(&ExpandParams {
                    v: [nw, nh, bw, bh, 1, 0, 0, 0],
                }),
                vec![maps_id[b + 1], maps_id[b]],
                tiles(bw, bh),
            );
        }
        let grid = Grid1::new(w * h);
        push(
            &mut map_steps,
            &mut layout,
            &pipelines.map_jod,
            bytemuck::bytes_of(&MapJodParams {
                size: [w * h, grid.x, 0, 0],
                values: [
                    p.jod_a * 0.1_f32.powf(p.jod_exp - 1.0),
                    p.jod_a,
                    p.jod_exp,
                    0.0,
                ],
            }),
            vec![maps_id[0]],
            [grid.x, grid.y],
        );

        use wgpu::util::DeviceExt;
        let uniforms = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("cvvdp uniforms"),
            contents: &layout.params,
            usage: wgpu::BufferUsages::UNIFORM,
        });
        let taps_uniform = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("cvvdp taps"),
            size: size_of::<TapsUniform>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let slot = |offset: u64, size: u64| {
            wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                buffer: &uniforms,
                offset,
                size: wgpu::BufferSize::new(size),
            })
        };
        let bind = |pipeline: &wgpu::ComputePipeline, entries: &[(u32, wgpu::BindingResource)]| {
            let entries: Vec<wgpu::BindGroupEntry> = entries
                .iter()
                .map(|(binding, r)| wgpu::BindGroupEntry {
                    binding: *binding,
                    resource: r.clone(),
                })
                .collect();
            device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: None,
                layout: &pipeline.get_bind_group_layout(0),
                entries: &entries,
            })
        };
        let make = |pending: Vec<Pending>| -> Vec<Step> {
            pending
                .into_iter()
                .map(|s| {
                    let mut entries = vec![(0, slot(s.slot, s.slot_size))];
                    for (i, &b) in s.buffers.iter().enumerate() {
                        entries.push((i as u32 + 1, whole(&all[b])));
                    }
                    Step {
                        bind: bind(&s.pipeline, &entries),
                        pipeline: s.pipeline,
                        groups: s.groups,
                    }
                })
                .collect()
        };
        let input = if key.linear {
            &pipelines.input_hdr
        } else {
            &pipelines.input_ldr
        };
        let mut input_entries = vec![
            (0, slot(input_slot, size_of::<InputParams>() as u64)),
            (1, whole(&taps_uniform)),
            (3, wgpu::BindingResource::TextureView(&ring_views[0])),
            (4, wgpu::BindingResource::TextureView(&ring_views[1])),
        ];
        let lut = device.create_texture_with_data(
            queue,
            &wgpu::TextureDescriptor {
                label: Some("cvvdp srgb decode"),
                size: wgpu::Extent3d {
                    width: 256,
                    height: 1,
                    depth_or_array_layers: 1,
                },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D1,
                format: wgpu::TextureFormat::R32Float,
                usage: wgpu::TextureUsages::TEXTURE_BINDING,
                view_formats: &[],
            },
            wgpu::util::TextureDataOrder::LayerMajor,
            bytemuck::cast_slice(&decode.srgb),
        );
        let lut_view = lut.create_view(&Default::default());
        if !key.linear {
            input_entries.push((2, wgpu::BindingResource::TextureView(&lut_view)));
        }
        for (i, b) in level[0].iter().enumerate() {
            input_entries.push((5 + i as u32, whole(b)));
        }
        let mut frame_steps = vec![Step {
            bind: bind(input, &input_entries),
            pipeline: input.clone(),
            groups: tiles(w, h),
        }];
        frame_steps.extend(make(steps));
        let map_steps = make(map_steps);
        Ok(Plan {
            key,
            channels,
            bands,
            taps,
            filters,
            ring,
            taps_uniform,
            partials,
            frame_partials,
            partials_buffer,
            map: maps[0].clone(),
            frame_steps,
            map_steps,
            _buffers: all,
            _lut: lut,
        })
    }

    /// Uploads frame `k` of the shot (test, reference) into its ring layer and the taps that
    /// frame `k` reads: frames `k - taps + 1 ..= k`, the ones before the shot's first replicated
    /// (the reference's default padding).
    pub fn upload_frame(&self, queue: &wgpu::Queue, k: usize, test: &[u8], reference: &[u8]) {
        let layer = (k % self.taps) as u32;
        let texel = if self.key.linear { 16 } else { 4 };
        for (texture, data) in self.ring.iter().zip([test, reference]) {
            queue.write_texture(
                wgpu::TexelCopyTextureInfo {
                    texture,
                    mip_level: 0,
                    origin: wgpu::Origin3d {
                        x: 0,
                        y: 0,
                        z: layer,
                    },
                    aspect: wgpu::TextureAspect::All,
                },
                data,
                wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(self.key.width * texel),
                    rows_per_image: Some(self.key.height),
                },
                wgpu::Extent3d {
                    width: self.key.width,
                    height: self.key.height,
                    depth_or_array_layers: 1,
                },
            );
        }
        let mut taps = TapsUniform {
            weights: [[0.0; 4]; MAX_TAPS],
            layers: [0; MAX_TAPS],
        };
        let n = self.taps;
        for j in 0..n {
            let index = (k + j).saturating_sub(n - 1);
            taps.layers[j] = (index % n) as u32;
            taps.weights[j] = std::array::from_fn(|c| self.filters[c][n - j - 1]);
        }
        queue.write_buffer(&self.taps_uniform, 0, bytemuck::bytes_of(&taps));
    }

    /// Records one frame's work (and its map's when `map`), in one compute pass.
    pub fn record_frame(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        map: bool,
        timestamps: Option<(&wgpu::QuerySet, u32)>,
    ) {
        let timestamp_writes = timestamps.map(|(set, i)| wgpu::ComputePassTimestampWrites {
            query_set: set,
            beginning_of_pass_write_index: Some(i),
            end_of_pass_write_index: Some(i + 1),
        });
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("cvvdp frame"),
            timestamp_writes,
        });
        let steps = self
            .frame_steps
            .iter()
            .chain(self.map_steps.iter().filter(|_| map));
        for s in steps {
            pass.set_pipeline(&s.pipeline);
            pass.set_bind_group(0, &s.bind, &[]);
            pass.dispatch_workgroups(s.groups[0], s.groups[1], 1);
        }
    }

    /// Copies the frame's partials to `staging` at `offset` (bytes).
    pub fn copy_partials(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        staging: &wgpu::Buffer,
        offset: u64,
    ) {
        encoder.copy_buffer_to_buffer(
            &self.partials_buffer,
            0,
            staging,
            offset,
            (self.frame_partials * 4) as u64,
        );
    }

    /// Copies the frame's distortion map to `staging` (offset 0).
    pub fn copy_map(&self, encoder: &mut wgpu::CommandEncoder, staging: &wgpu::Buffer) {
        encoder.copy_buffer_to_buffer(
            &self.map,
            0,
            staging,
            0,
            self.key.width as u64 * self.key.height as u64 * 4,
        );
    }
}

fn internal() -> GpuMetricsError {
    GpuMetricsError::Unsupported("ColorVideoVDP plan: partial regions out of step".into())
}
