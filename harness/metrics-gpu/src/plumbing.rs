//! The plumbing every metric pass shares, below the state that owns the device: 1-D dispatch
//! grids, a request's uniform slots and output regions, pixels packed one per u32, the binding
//! limit check and the one blocking readback.
//!
//! For: shapes and helpers that hold no GPU object of their own. Not for: owning pipelines or
//! buffers (`context`), or what a pass computes (`pair`, `temporal`, `frame`, `cvvdp`, `pool`).

use tessera_metrics::Rgb8Image;

use crate::error::GpuMetricsError;

/// Threads per workgroup of the 1-D passes.
pub(crate) const GROUP: u32 = 256;
/// Workgroups per row of a 1-D dispatch (the rest go to further rows).
const MAX_GROUPS_X: u32 = 32768;
/// Alignment of uniform slots and output regions (the largest minimum offset alignment).
const ALIGN: u64 = 256;
/// Metric groups timed per request, at most (two timestamps each).
pub(crate) const MAX_TIMED: u32 = 16;

/// A 1-D grid of 256-thread workgroups covering `count` items.
#[derive(Clone, Copy)]
pub(crate) struct Grid1 {
    pub x: u32,
    pub y: u32,
}

impl Grid1 {
    pub fn new(count: u32) -> Grid1 {
        let groups = count.div_ceil(GROUP).max(1);
        let x = groups.min(MAX_GROUPS_X);
        Grid1 {
            x,
            y: groups.div_ceil(x),
        }
    }
    pub fn groups(&self) -> u32 {
        self.x * self.y
    }
}

/// Uniform slots and output regions of one request, laid out before anything is recorded.
#[derive(Default)]
pub(crate) struct Layout {
    pub params: Vec<u8>,
    pub outputs: u64,
}

impl Layout {
    /// Appends a uniform slot; returns its offset.
    pub fn param<T: bytemuck::Pod>(&mut self, value: &T) -> u64 {
        let offset = self.params.len() as u64;
        self.params.extend_from_slice(bytemuck::bytes_of(value));
        self.params
            .resize(offset as usize + align(size_of::<T>() as u64) as usize, 0);
        offset
    }
    /// Reserves an output region of `bytes`; returns its offset.
    pub fn output(&mut self, bytes: u64) -> Region {
        let offset = self.outputs;
        self.outputs += align(bytes.max(4));
        Region {
            offset,
            size: bytes.max(4),
        }
    }
}

/// Part of the output buffer.
#[derive(Clone, Copy)]
pub(crate) struct Region {
    pub offset: u64,
    pub size: u64,
}

fn align(v: u64) -> u64 {
    v.div_ceil(ALIGN) * ALIGN
}

/// Packs 8-bit RGB into one u32 per pixel.
pub(crate) fn pack(image: &Rgb8Image) -> Vec<u32> {
    image
        .data
        .chunks_exact(3)
        .map(|p| p[0] as u32 | (p[1] as u32) << 8 | (p[2] as u32) << 16)
        .collect()
}

/// Unpacks `count` pixels.
pub(crate) fn unpack(words: &[u32], width: u32, height: u32) -> Rgb8Image {
    let n = width as usize * height as usize;
    let data = words[..n]
        .iter()
        .flat_map(|&p| [p as u8, (p >> 8) as u8, (p >> 16) as u8])
        .collect();
    Rgb8Image {
        width,
        height,
        data,
    }
}

/// Checks that one binding of `bytes` fits `device`'s limits.
pub(crate) fn check_binding(
    device: &wgpu::Device,
    what: &str,
    bytes: u64,
) -> Result<(), GpuMetricsError> {
    let limits = device.limits();
    let max = limits
        .max_storage_buffer_binding_size
        .min(limits.max_buffer_size);
    if bytes > max {
        return Err(GpuMetricsError::Unsupported(format!(
            "{what} needs a {bytes}-byte storage buffer; the device allows {max}"
        )));
    }
    Ok(())
}

/// Maps the first `size` bytes of `buffer` (after the submission that fills it) and copies them.
pub(crate) fn read_buffer(
    device: &wgpu::Device,
    buffer: &wgpu::Buffer,
    size: u64,
) -> Result<Vec<u8>, GpuMetricsError> {
    let size = size.div_ceil(4) * 4;
    let slice = buffer.slice(..size);
    let (tx, rx) = std::sync::mpsc::channel();
    slice.map_async(wgpu::MapMode::Read, move |r| {
        let _ = tx.send(r);
    });
    let _ = device.poll(wgpu::PollType::Wait {
        submission_index: None,
        timeout: None,
    });
    rx.recv()
        .map_err(|e| GpuMetricsError::Readback(e.to_string()))?
        .map_err(|e| GpuMetricsError::Readback(e.to_string()))?;
    let bytes = slice
        .get_mapped_range()
        .map_err(|e| GpuMetricsError::Readback(format!("{e:?}")))?
        .to_vec();
    buffer.unmap();
    Ok(bytes)
}
