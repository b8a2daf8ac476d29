//! The raw Vulkan passes of `adaptive-shading`'s hardware path and `native-vrs`
//! (VK_KHR_fragment_shading_rate beside wgpu: the only raw Vulkan passes in Tessera): a depth
//! pre-pass and a forward pass drawn with a fragment-shading-rate attachment. The device with the
//! extension turned on is `gpu/vrs.rs`'s.
//!
//! Two shapes (`hardware.rs` drives them):
//! - **split** (`adaptive-shading`, the paper's order of work, section 5): [`RawVrsPass::record_prepass`]
//!   is a render pass of its own that clears this frame's depth and draws it with the motion
//!   target (`fs_vrs_motion`); wgpu's rate passes then read that motion; [`RawVrsPass::record_shade`]
//!   clears the colour, loads the depth and shades at the attachment's rates (depth test EQUAL,
//!   no depth writes).
//! - **single** (`native-vrs`): one render pass that clears colour and depth, draws the depth
//!   pre-pass (vertex shader only), then shades (EQUAL): no motion, as `native` has none.
//!
//! The clears are the render passes' load ops (`native`'s forward pass clears the same way); no
//! separate clear pass. How the passes fit into wgpu's frame: before each, `hardware.rs` moves
//! the targets into COLOR_TARGET / DEPTH_STENCIL_WRITE with `CommandEncoder::transition_resources`
//! (COLOR_ATTACHMENT_OPTIMAL / DEPTH_STENCIL_ATTACHMENT_OPTIMAL, what these render passes begin
//! and end in), so wgpu's tracked state stays true; the targets were initialised once by a wgpu
//! clear when the renderer was built, so wgpu never clears them lazily over what these passes
//! wrote. Each pass records into a command encoder of its own (wgpu forbids mixing raw and wgpu
//! commands in one encoder): a full memory barrier, its render pass, another full barrier; the
//! shading pass also copies the attachment bytes (written by a wgpu compute pass into a wgpu
//! buffer) into the R8_UINT attachment image this module owns. The encoders are submitted
//! together, in order.
//!
//! The pipelines are the project's WGSL (`scene.wgsl` + `adaptive_shading/vrs.wgsl`) compiled to
//! SPIR-V by naga with the options wgpu uses (no coordinate flip in the shader; the viewport is
//! flipped, as wgpu-hal does); the shading pipeline has
//! `VkPipelineFragmentShadingRateStateCreateInfoKHR` at 1x1 and combiner ops (KEEP, REPLACE): the
//! attachment alone decides the rate. Fragment-shader invocations of the shading pass and of the
//! motion pre-pass are counted by pipeline-statistics queries of this module's own.
//!
//! Textured materials: after the untextured objects, each pass draws the scene's textured draws
//! (`MaterialGpu`'s: `MaterialVertex` buffers, instanced placements, a descriptor set per material
//! bind group from `raw_material.rs`) with pipelines from `vrs_material.wgsl` (sets 0 and 1 as
//! `material.rs`'s wgpu layout): in a pre-pass opaque and alpha-tested draws (the alpha test at
//! 1x1, no shading-rate state), in the shading pass opaque and alpha-tested draws at EQUAL and then
//! blended draws in this frame's back-to-front order (GREATER, no depth writes, wgpu's
//! `ALPHA_BLENDING`), both at the attachment's rates.
//!
//! Not here: which rates (the rate pass and the CPU model, this folder's `gpu.rs` and `model.rs`),
//! timing (wgpu-profiler timestamps around the encoders).

use ash::vk;
use wgpu::hal::api::Vulkan;

use super::raw_material::{raw_buffer, RawMaterialSets};
use super::raw_pipeline::{ColorOut, RawPipeline};
use crate::render::material::{Class, RawMaterials};
use crate::render::scene::RawDraw;

/// The targets of one frame parity: colour (Rgba16Float) and depth (Depth32Float), and the motion
/// target (Rgba16Float) of the split shape, all `width` x `height`, as wgpu allocated them.
pub struct Targets<'a> {
    pub color: &'a wgpu::Texture,
    pub depth: &'a wgpu::Texture,
    pub motion: Option<&'a wgpu::Texture>,
}

/// Where the passes' SPIR-V comes from: one WGSL module and its entry points; `motion_fragment`
/// (the motion pre-pass) makes the shape split.
pub struct Shaders<'a> {
    pub wgsl: &'a str,
    pub vertex: &'a str,
    pub fragment: &'a str,
    pub motion_fragment: Option<&'a str>,
    /// The textured draws' WGSL (`scene.wgsl` + `material.wgsl` + `vrs_material.wgsl`, entry
    /// points [`MATERIAL_ENTRY_POINTS`]); needed when the scene has textured models.
    pub material: Option<&'a str>,
}

/// The entry points of the textured draws' pipelines (`vrs_material.wgsl`), in the order of
/// [`RawVrsPass`]'s material modules: vertex, shading, opaque motion, alpha-tested motion,
/// alpha-tested depth.
pub const MATERIAL_ENTRY_POINTS: [(naga::ShaderStage, &str); 5] = [
    (naga::ShaderStage::Vertex, "vs_vrs_material"),
    (naga::ShaderStage::Fragment, "fs_vrs_material"),
    (naga::ShaderStage::Fragment, "fs_vrs_material_motion"),
    (naga::ShaderStage::Fragment, "fs_vrs_material_motion_mask"),
    (naga::ShaderStage::Fragment, "fs_vrs_material_depth_mask"),
];

/// The attributes of `MaterialVertex` (position, normal, uv, tangent) at location 0..=3.
const MATERIAL_ATTRIBUTES: [(vk::Format, u32); 4] = [
    (vk::Format::R32G32B32_SFLOAT, 0),
    (vk::Format::R32G32B32_SFLOAT, 12),
    (vk::Format::R32G32_SFLOAT, 24),
    (vk::Format::R32G32B32A32_SFLOAT, 32),
];

/// Query indices in the statistics pool.
const SHADE_QUERY: u32 = 0;
const PREPASS_QUERY: u32 = 1;

/// The raw objects of the passes: render passes and framebuffers (one per parity), the
/// attachment image, the pipelines and their descriptor set, the statistics queries.
pub struct RawVrsPass {
    device: ash::Device,
    size: [u32; 2],
    attachment_size: [u32; 2],
    /// Colour, depth and rate attachment; depth loaded (split) or cleared (single).
    shade_pass: vk::RenderPass,
    /// Split shape only: motion and depth, depth cleared.
    motion_pass: vk::RenderPass,
    shade_framebuffers: Vec<vk::Framebuffer>,
    motion_framebuffers: Vec<vk::Framebuffer>,
    views: Vec<vk::ImageView>,
    rate_image: vk::Image,
    rate_memory: vk::DeviceMemory,
    set_layout: vk::DescriptorSetLayout,
    pool: vk::DescriptorPool,
    set: vk::DescriptorSet,
    layout: vk::PipelineLayout,
    /// The shading draw (EQUAL, rates from the attachment).
    pipeline: vk::Pipeline,
    /// Single shape: the depth pre-pass in the shading render pass (vertex shader only).
    depth_prepass: vk::Pipeline,
    /// Split shape: the motion pre-pass (depth and motion) in its own render pass.
    motion_prepass: vk::Pipeline,
    /// Vertex, fragment, motion fragment (null in the single shape).
    modules: [vk::ShaderModule; 3],
    stats: vk::QueryPool,
    /// Whether a shading pass / a pre-pass query was ever recorded.
    recorded: [bool; 2],
    /// wgpu objects the raw handles point into, kept alive as long as the pass.
    _keep_textures: Vec<wgpu::Texture>,
    _keep_buffers: Vec<wgpu::Buffer>,
    vertex: vk::Buffer,
    index: vk::Buffer,
    staging: vk::Buffer,
    draws: Vec<(u32, u32, i32)>,
    /// Whether the shading pass has the rate attachment (always, but for
    /// [`RawVrsPass::new`] without a texel size: the raw drawing tested where the extension is
    /// missing).
    rated: bool,
    /// The scene's textured draws and their descriptor sets (`None` on an untextured scene).
    materials: Option<RawMaterialSets>,
    /// Sets 0 (scene) and 1 (material) of the textured draws' pipelines.
    material_layout: vk::PipelineLayout,
    /// Of [`MATERIAL_ENTRY_POINTS`], in its order.
    material_modules: [vk::ShaderModule; 5],
    /// Shading: opaque and alpha-tested draws (EQUAL, no depth writes), blended draws (GREATER,
    /// no depth writes, blended).
    material_shade: [vk::Pipeline; 2],
    /// The pre-pass (motion in the split shape, depth alone in the single one): opaque draws,
    /// alpha-tested draws (the alpha test at full rate).
    material_prepass: [vk::Pipeline; 2],
}

/// Which of a frame's passes draws the textured models.
#[derive(Clone, Copy, PartialEq)]
enum Phase {
    Prepass,
    Shade,
}

/// SPIR-V of one entry point of `wgsl`, with the options wgpu-hal uses on Vulkan (bindings by
/// group and binding, no coordinate adjustment).
pub fn spirv(wgsl: &str, stage: naga::ShaderStage, entry: &str) -> Result<Vec<u32>, String> {
    let module = naga::front::wgsl::parse_str(wgsl).map_err(|e| e.emit_to_string(wgsl))?;
    let info = naga::valid::Validator::new(
        naga::valid::ValidationFlags::all(),
        naga::valid::Capabilities::all(),
    )
    .validate(&module)
    .map_err(|e| e.emit_to_string(wgsl))?;
    let options = naga::back::spv::Options {
        lang_version: (1, 3),
        flags: naga::back::spv::WriterFlags::LABEL_VARYINGS,
        ..Default::default()
    };
    let pipeline = naga::back::spv::PipelineOptions {
        shader_stage: stage,
        entry_point: entry.to_string(),
    };
    naga::back::spv::write_vec(&module, &info, &options, Some(&pipeline)).map_err(|e| e.to_string())
}

/// Group 0 of `scene.wgsl` as the raw layout binds it: binding, descriptor type (the frame
/// uniforms, the objects; checked against the shader by `tests/vrs.rs`).
pub fn scene_bindings() -> Vec<(u32, vk::DescriptorType)> {
    vec![
        (0, vk::DescriptorType::UNIFORM_BUFFER),
        (1, vk::DescriptorType::STORAGE_BUFFER),
    ]
}

fn vk_err(what: &'static str) -> impl Fn(vk::Result) -> String {
    move |e| format!("{what}: {e}")
}

/// The SPIR-V of the passes: the untextured vertex, shading and motion fragment shaders, and
/// the textured draws' [`MATERIAL_ENTRY_POINTS`] where the scene has textured models.
struct PassSpirv {
    vertex: Vec<u32>,
    fragment: Vec<u32>,
    motion: Option<Vec<u32>>,
    material: Option<Vec<Vec<u32>>>,
}

impl PassSpirv {
    fn compile(shaders: &Shaders<'_>, textured: bool) -> Result<PassSpirv, String> {
        let material = match (textured, shaders.material) {
            (false, _) => None,
            (true, None) => {
                return Err("the scene has textured draws and no material shader was given".into())
            }
            (true, Some(wgsl)) => Some(
                MATERIAL_ENTRY_POINTS
                    .iter()
                    .map(|&(stage, entry)| spirv(wgsl, stage, entry))
                    .collect::<Result<Vec<_>, String>>()?,
            ),
        };
        let motion = match shaders.motion_fragment {
            Some(entry) => Some(spirv(shaders.wgsl, naga::ShaderStage::Fragment, entry)?),
            None => None,
        };
        Ok(PassSpirv {
            vertex: spirv(shaders.wgsl, naga::ShaderStage::Vertex, shaders.vertex)?,
            fragment: spirv(shaders.wgsl, naga::ShaderStage::Fragment, shaders.fragment)?,
            motion,
            material,
        })
    }
}

/// What the passes need of wgpu's Vulkan objects: the raw device, the physical device's memory
/// types, and the raw formats of the colour, depth and motion targets.
fn raw_device(
    device: &wgpu::Device,
    adapter: &wgpu::Adapter,
    target: &Targets<'_>,
) -> Result<
    (
        ash::Device,
        vk::PhysicalDeviceMemoryProperties,
        [vk::Format; 3],
    ),
    String,
> {
    // SAFETY: read-only access to the hal objects for their raw handles; wgpu keeps ownership
    // and the pass's clones keep every object alive as long as it.
    unsafe {
        let hal_device = device.as_hal::<Vulkan>().ok_or("not a Vulkan device")?;
        let hal_adapter = adapter.as_hal::<Vulkan>().ok_or("not a Vulkan adapter")?;
        let instance = hal_device.shared_instance().raw_instance();
        let memory =
            instance.get_physical_device_memory_properties(hal_device.raw_physical_device());
        let formats = [
            hal_adapter.texture_format_as_raw(target.color.format()),
            hal_adapter.texture_format_as_raw(target.depth.format()),
            hal_adapter.texture_format_as_raw(
                target
                    .motion
                    .map(|m| m.format())
                    .unwrap_or(target.color.format()),
            ),
        ];
        Ok((hal_device.raw_device().clone(), memory, formats))
    }
}

fn image_of(t: &wgpu::Texture) -> Result<vk::Image, String> {
    // SAFETY: the handle is only used while `t` (kept in `_keep_textures`) is alive.
    unsafe { t.as_hal::<Vulkan>().map(|h| h.raw_handle()) }
        .ok_or_else(|| "texture is not a Vulkan texture".to_string())
}

/// The untextured scene vertex's attributes (position, normal) at location 0 and 1.
const SCENE_ATTRIBUTES: [(vk::Format, u32); 2] = [
    (vk::Format::R32G32B32_SFLOAT, 0),
    (vk::Format::R32G32B32_SFLOAT, 12),
];

fn attachment(
    format: vk::Format,
    layout: vk::ImageLayout,
    load: vk::AttachmentLoadOp,
) -> vk::AttachmentDescription2<'static> {
    vk::AttachmentDescription2::default()
        .format(format)
        .samples(vk::SampleCountFlags::TYPE_1)
        .load_op(load)
        .store_op(vk::AttachmentStoreOp::STORE)
        .stencil_load_op(vk::AttachmentLoadOp::DONT_CARE)
        .stencil_store_op(vk::AttachmentStoreOp::DONT_CARE)
        .initial_layout(layout)
        .final_layout(layout)
}

fn reference(i: u32, layout: vk::ImageLayout) -> vk::AttachmentReference2<'static> {
    vk::AttachmentReference2::default()
        .attachment(i)
        .layout(layout)
}

const COLOR_LAYOUT: vk::ImageLayout = vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL;
const DEPTH_LAYOUT: vk::ImageLayout = vk::ImageLayout::DEPTH_STENCIL_ATTACHMENT_OPTIMAL;
const RATE_LAYOUT: vk::ImageLayout = vk::ImageLayout::FRAGMENT_SHADING_RATE_ATTACHMENT_OPTIMAL_KHR;

impl RawVrsPass {
    /// Builds the passes for `targets` (one per frame parity) at `size`, with an attachment of
    /// `attachment_size` texels of `texel` pixels filled each frame from `staging` (tightly packed
    /// bytes), drawing `scene` and its textured `materials`; split when `shaders.motion_fragment`
    /// is given (every target then needs its motion). Without `texel` the shading pass has no
    /// rate attachment and its pipelines no shading-rate state: every pixel shaded once, on any
    /// Vulkan device (how the raw drawing is tested where the extension is missing).
    ///
    /// The steps, each a method below: the attachment image, the render passes, the
    /// framebuffers, the scene's descriptor set and shader modules, the untextured pipelines,
    /// the textured draws' pipelines, the statistics queries. Each object is stored in the pass
    /// as soon as it exists, so `Drop` destroys exactly what was made, also when a later step
    /// fails.
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        device: &wgpu::Device,
        adapter: &wgpu::Adapter,
        shaders: &Shaders<'_>,
        targets: &[Targets<'_>],
        size: [u32; 2],
        texel: Option<[u32; 2]>,
        attachment_size: [u32; 2],
        staging: &wgpu::Buffer,
        scene: &RawDraw<'_>,
        materials: Option<&RawMaterials<'_>>,
    ) -> Result<RawVrsPass, String> {
        let split = shaders.motion_fragment.is_some();
        if split && targets.iter().any(|t| t.motion.is_none()) {
            return Err("the motion pre-pass needs a motion target for every parity".into());
        }
        let code = PassSpirv::compile(shaders, materials.is_some())?;
        let anisotropic = adapter
            .get_downlevel_capabilities()
            .flags
            .contains(wgpu::DownlevelFlags::ANISOTROPIC_FILTERING);
        let (raw, memory, formats) = raw_device(device, adapter, &targets[0])?;
        let mut pass = RawVrsPass::empty(raw, size, attachment_size, texel.is_some());
        pass._keep_textures = targets
            .iter()
            .flat_map(|t| [Some(t.color), Some(t.depth), t.motion])
            .flatten()
            .cloned()
            .collect();
        pass._keep_buffers = vec![
            scene.vertex.clone(),
            scene.index.clone(),
            scene.frame.clone(),
            scene.objects.clone(),
            staging.clone(),
        ];
        // The buffers are kept in `_keep_buffers` while the pass lives.
        pass.vertex = raw_buffer(scene.vertex)?;
        pass.index = raw_buffer(scene.index)?;
        pass.staging = raw_buffer(staging)?;
        pass.draws = scene.draws.clone();

        let rate_view = if pass.rated {
            pass.create_attachment_image(&memory)?
        } else {
            vk::ImageView::null()
        };
        pass.create_render_passes(formats, texel.unwrap_or([1, 1]), split)?;
        pass.create_framebuffers(targets, formats, rate_view, split)?;
        pass.create_scene_set(scene)?;
        pass.create_modules(&code)?;
        pass.create_scene_pipelines(shaders, scene.vertex_stride, split)?;
        if let (Some(raw), Some(code)) = (materials, &code.material) {
            pass.materials = RawMaterialSets::new(&pass.device.clone(), raw, anisotropic)?;
            pass.create_material_pipelines(code, split)?;
        }
        pass.create_statistics()?;
        Ok(pass)
    }

    /// A pass with no Vulkan object made yet (every handle null).
    fn empty(
        device: ash::Device,
        size: [u32; 2],
        attachment_size: [u32; 2],
        rated: bool,
    ) -> RawVrsPass {
        RawVrsPass {
            device,
            size,
            attachment_size,
            shade_pass: vk::RenderPass::null(),
            motion_pass: vk::RenderPass::null(),
            shade_framebuffers: Vec::new(),
            motion_framebuffers: Vec::new(),
            views: Vec::new(),
            rate_image: vk::Image::null(),
            rate_memory: vk::DeviceMemory::null(),
            set_layout: vk::DescriptorSetLayout::null(),
            pool: vk::DescriptorPool::null(),
            set: vk::DescriptorSet::null(),
            layout: vk::PipelineLayout::null(),
            pipeline: vk::Pipeline::null(),
            depth_prepass: vk::Pipeline::null(),
            motion_prepass: vk::Pipeline::null(),
            modules: [vk::ShaderModule::null(); 3],
            stats: vk::QueryPool::null(),
            recorded: [false; 2],
            _keep_textures: Vec::new(),
            _keep_buffers: Vec::new(),
            vertex: vk::Buffer::null(),
            index: vk::Buffer::null(),
            staging: vk::Buffer::null(),
            draws: Vec::new(),
            rated,
            materials: None,
            material_layout: vk::PipelineLayout::null(),
            material_modules: [vk::ShaderModule::null(); 5],
            material_shade: [vk::Pipeline::null(); 2],
            material_prepass: [vk::Pipeline::null(); 2],
        }
    }

    /// A 2D view of one mip and layer of `image`, kept in `views` (destroyed in `Drop`).
    fn view(
        &mut self,
        image: vk::Image,
        format: vk::Format,
        aspect: vk::ImageAspectFlags,
    ) -> Result<vk::ImageView, String> {
        let info = vk::ImageViewCreateInfo::default()
            .image(image)
            .view_type(vk::ImageViewType::TYPE_2D)
            .format(format)
            .subresource_range(vk::ImageSubresourceRange {
                aspect_mask: aspect,
                base_mip_level: 0,
                level_count: 1,
                base_array_layer: 0,
                layer_count: 1,
            });
        // SAFETY: `image` is alive (ours or a kept wgpu texture's) and the view matches its
        // format, type and single mip and layer.
        let v =
            unsafe { self.device.create_image_view(&info, None) }.map_err(vk_err("image view"))?;
        self.views.push(v);
        Ok(v)
    }

    /// The attachment image (R8_UINT, device-local, written by a copy) and its view.
    fn create_attachment_image(
        &mut self,
        memory: &vk::PhysicalDeviceMemoryProperties,
    ) -> Result<vk::ImageView, String> {
        let d = self.device.clone();
        let info = vk::ImageCreateInfo::default()
            .image_type(vk::ImageType::TYPE_2D)
            .format(vk::Format::R8_UINT)
            .extent(vk::Extent3D {
                width: self.attachment_size[0],
                height: self.attachment_size[1],
                depth: 1,
            })
            .mip_levels(1)
            .array_layers(1)
            .samples(vk::SampleCountFlags::TYPE_1)
            .tiling(vk::ImageTiling::OPTIMAL)
            .usage(
                vk::ImageUsageFlags::FRAGMENT_SHADING_RATE_ATTACHMENT_KHR
                    | vk::ImageUsageFlags::TRANSFER_DST,
            )
            .initial_layout(vk::ImageLayout::UNDEFINED);
        // SAFETY: the create-infos outlive their calls; the image and memory are stored in the
        // pass as soon as they exist.
        unsafe {
            self.rate_image = d
                .create_image(&info, None)
                .map_err(vk_err("attachment image"))?;
            let req = d.get_image_memory_requirements(self.rate_image);
            let types = &memory.memory_types[..memory.memory_type_count as usize];
            let pick = |flags: vk::MemoryPropertyFlags| {
                types.iter().enumerate().position(|(i, t)| {
                    req.memory_type_bits & (1 << i) != 0 && t.property_flags.contains(flags)
                })
            };
            let type_index = pick(vk::MemoryPropertyFlags::DEVICE_LOCAL)
                .or_else(|| pick(vk::MemoryPropertyFlags::empty()))
                .ok_or("no memory type for the attachment image")?;
            let alloc = vk::MemoryAllocateInfo::default()
                .allocation_size(req.size)
                .memory_type_index(type_index as u32);
            self.rate_memory = d
                .allocate_memory(&alloc, None)
                .map_err(vk_err("attachment memory"))?;
            d.bind_image_memory(self.rate_image, self.rate_memory, 0)
                .map_err(vk_err("binding attachment memory"))?;
        }
        self.view(
            self.rate_image,
            vk::Format::R8_UINT,
            vk::ImageAspectFlags::COLOR,
        )
    }

    /// Render passes. Colour targets begin and end in COLOR_ATTACHMENT_OPTIMAL, depth in
    /// DEPTH_STENCIL_ATTACHMENT_OPTIMAL (what wgpu's transitions left them in); a cleared
    /// target's old contents are not read.
    fn create_render_passes(
        &mut self,
        formats: [vk::Format; 3],
        texel: [u32; 2],
        split: bool,
    ) -> Result<(), String> {
        let clear = vk::AttachmentLoadOp::CLEAR;
        // The shading pass: colour (cleared), depth (the pre-pass's in the split shape, else
        // cleared), the rate attachment (read only).
        let depth_load = if split {
            vk::AttachmentLoadOp::LOAD
        } else {
            clear
        };
        let all_attachments = [
            attachment(formats[0], COLOR_LAYOUT, clear),
            attachment(formats[1], DEPTH_LAYOUT, depth_load),
            attachment(vk::Format::R8_UINT, RATE_LAYOUT, vk::AttachmentLoadOp::LOAD)
                .store_op(vk::AttachmentStoreOp::DONT_CARE),
        ];
        let attachments = &all_attachments[..if self.rated { 3 } else { 2 }];
        let color_refs = [reference(0, COLOR_LAYOUT)];
        let depth_ref = reference(1, DEPTH_LAYOUT);
        let rate_ref = reference(2, RATE_LAYOUT);
        let mut rate_info = vk::FragmentShadingRateAttachmentInfoKHR::default()
            .fragment_shading_rate_attachment(&rate_ref)
            .shading_rate_attachment_texel_size(vk::Extent2D {
                width: texel[0],
                height: texel[1],
            });
        let subpass = vk::SubpassDescription2::default()
            .pipeline_bind_point(vk::PipelineBindPoint::GRAPHICS)
            .color_attachments(&color_refs)
            .depth_stencil_attachment(&depth_ref);
        let subpass = if self.rated {
            subpass.push_next(&mut rate_info)
        } else {
            subpass
        };
        let subpasses = [subpass];
        let rp_info = vk::RenderPassCreateInfo2::default()
            .attachments(attachments)
            .subpasses(&subpasses);
        // SAFETY: the create-info chain (attachments, subpass, shading-rate attachment info)
        // lives across the call; the extension is enabled on this device (`open`).
        self.shade_pass = unsafe { self.device.create_render_pass2(&rp_info, None) }
            .map_err(vk_err("render pass"))?;
        if split {
            // The motion pre-pass: motion (not cleared: read only where depth is drawn), depth
            // (cleared).
            let attachments = [
                attachment(formats[2], COLOR_LAYOUT, vk::AttachmentLoadOp::DONT_CARE),
                attachment(formats[1], DEPTH_LAYOUT, clear),
            ];
            let subpass = vk::SubpassDescription2::default()
                .pipeline_bind_point(vk::PipelineBindPoint::GRAPHICS)
                .color_attachments(&color_refs)
                .depth_stencil_attachment(&depth_ref);
            let subpasses = [subpass];
            let rp_info = vk::RenderPassCreateInfo2::default()
                .attachments(&attachments)
                .subpasses(&subpasses);
            // SAFETY: as above.
            self.motion_pass = unsafe { self.device.create_render_pass2(&rp_info, None) }
                .map_err(vk_err("motion render pass"))?;
        }
        Ok(())
    }

    /// One framebuffer per target (and per motion target in the split shape).
    fn create_framebuffers(
        &mut self,
        targets: &[Targets<'_>],
        formats: [vk::Format; 3],
        rate_view: vk::ImageView,
        split: bool,
    ) -> Result<(), String> {
        let size = self.size;
        let framebuffer = |d: &ash::Device, render_pass, views: &[vk::ImageView]| {
            let info = vk::FramebufferCreateInfo::default()
                .render_pass(render_pass)
                .attachments(views)
                .width(size[0])
                .height(size[1])
                .layers(1);
            // SAFETY: the views are alive and match the render pass's attachments; the rate
            // view covers ceil(size / texel) texels as the framebuffer size requires.
            unsafe { d.create_framebuffer(&info, None) }.map_err(vk_err("framebuffer"))
        };
        let d = self.device.clone();
        for t in targets {
            let c = self.view(image_of(t.color)?, formats[0], vk::ImageAspectFlags::COLOR)?;
            let z = self.view(image_of(t.depth)?, formats[1], vk::ImageAspectFlags::DEPTH)?;
            let all_views = [c, z, rate_view];
            let views = &all_views[..if self.rated { 3 } else { 2 }];
            let fb = framebuffer(&d, self.shade_pass, views)?;
            self.shade_framebuffers.push(fb);
            if let (true, Some(m)) = (split, t.motion) {
                let m = self.view(image_of(m)?, formats[2], vk::ImageAspectFlags::COLOR)?;
                let fb = framebuffer(&d, self.motion_pass, &[m, z])?;
                self.motion_framebuffers.push(fb);
            }
        }
        Ok(())
    }

    /// The descriptor set of group 0 of scene.wgsl (frame uniforms, objects) and its pipeline
    /// layout.
    fn create_scene_set(&mut self, scene: &RawDraw<'_>) -> Result<(), String> {
        let frame = raw_buffer(scene.frame)?;
        let objects = raw_buffer(scene.objects)?;
        let stages = vk::ShaderStageFlags::VERTEX | vk::ShaderStageFlags::FRAGMENT;
        let bindings: Vec<vk::DescriptorSetLayoutBinding> = scene_bindings()
            .into_iter()
            .map(|(binding, ty)| {
                vk::DescriptorSetLayoutBinding::default()
                    .binding(binding)
                    .descriptor_type(ty)
                    .descriptor_count(1)
                    .stage_flags(stages)
            })
            .collect();
        let pool_sizes = [
            vk::DescriptorPoolSize {
                ty: vk::DescriptorType::UNIFORM_BUFFER,
                descriptor_count: 1,
            },
            vk::DescriptorPoolSize {
                ty: vk::DescriptorType::STORAGE_BUFFER,
                descriptor_count: 1,
            },
        ];
        let d = self.device.clone();
        // SAFETY: create-infos outlive their calls; the set is written with buffers that the
        // pass keeps alive, at the offset and size scene.wgsl's layout expects.
        unsafe {
            self.set_layout = d
                .create_descriptor_set_layout(
                    &vk::DescriptorSetLayoutCreateInfo::default().bindings(&bindings),
                    None,
                )
                .map_err(vk_err("descriptor set layout"))?;
            self.pool = d
                .create_descriptor_pool(
                    &vk::DescriptorPoolCreateInfo::default()
                        .max_sets(1)
                        .pool_sizes(&pool_sizes),
                    None,
                )
                .map_err(vk_err("descriptor pool"))?;
            let layouts = [self.set_layout];
            self.set = d
                .allocate_descriptor_sets(
                    &vk::DescriptorSetAllocateInfo::default()
                        .descriptor_pool(self.pool)
                        .set_layouts(&layouts),
                )
                .map_err(vk_err("descriptor set"))?[0];
            let frame_info = [vk::DescriptorBufferInfo {
                buffer: frame,
                offset: scene.frame_offset,
                range: scene.frame_size,
            }];
            let objects_info = [vk::DescriptorBufferInfo {
                buffer: objects,
                offset: 0,
                range: vk::WHOLE_SIZE,
            }];
            let writes = [
                vk::WriteDescriptorSet::default()
                    .dst_set(self.set)
                    .dst_binding(0)
                    .descriptor_type(vk::DescriptorType::UNIFORM_BUFFER)
                    .buffer_info(&frame_info),
                vk::WriteDescriptorSet::default()
                    .dst_set(self.set)
                    .dst_binding(1)
                    .descriptor_type(vk::DescriptorType::STORAGE_BUFFER)
                    .buffer_info(&objects_info),
            ];
            d.update_descriptor_sets(&writes, &[]);
            self.layout = d
                .create_pipeline_layout(
                    &vk::PipelineLayoutCreateInfo::default().set_layouts(&layouts),
                    None,
                )
                .map_err(vk_err("pipeline layout"))?;
        }
        Ok(())
    }

    /// The shader modules of the untextured draws.
    fn create_modules(&mut self, code: &PassSpirv) -> Result<(), String> {
        let words = [
            Some(&code.vertex),
            Some(&code.fragment),
            code.motion.as_ref(),
        ];
        let names = ["vertex shader", "fragment shader", "motion fragment shader"];
        for (i, (words, what)) in words.into_iter().zip(names).enumerate() {
            if let Some(words) = words {
                // SAFETY: the create-info outlives the call; the module is stored at once.
                self.modules[i] = unsafe {
                    self.device.create_shader_module(
                        &vk::ShaderModuleCreateInfo::default().code(words),
                        None,
                    )
                }
                .map_err(vk_err(what))?;
            }
        }
        Ok(())
    }

    /// The untextured pipelines: the shading draw (EQUAL against the pre-pass's depth, no depth
    /// writes: each covered pixel is shaded by its visible primitive only, so at 1x1 the
    /// invocation count is the covered pixels exactly, the shade-count model's premise), and the
    /// pre-pass (depth test GREATER and write): with the motion target in its own render pass
    /// (split) or depth alone in the shading render pass (single). The same vertex shader
    /// throughout (its position is `@invariant`).
    fn create_scene_pipelines(
        &mut self,
        shaders: &Shaders<'_>,
        stride: u32,
        split: bool,
    ) -> Result<(), String> {
        let vs_name = std::ffi::CString::new(shaders.vertex).map_err(|e| e.to_string())?;
        let fs_name = std::ffi::CString::new(shaders.fragment).map_err(|e| e.to_string())?;
        let motion_name = std::ffi::CString::new(shaders.motion_fragment.unwrap_or("none"))
            .map_err(|e| e.to_string())?;
        let shade = RawPipeline {
            layout: self.layout,
            render_pass: self.shade_pass,
            stride,
            attributes: &SCENE_ATTRIBUTES,
            vertex: (self.modules[0], &vs_name),
            fragment: Some((self.modules[1], &fs_name)),
            depth: (vk::CompareOp::EQUAL, false),
            color: ColorOut::Write,
            rates: self.rated,
        };
        let d = self.device.clone();
        // SAFETY: the modules, layout and render passes are alive; the shading-rate state is
        // chained only where the device has the extension (`rated`).
        unsafe {
            self.pipeline = shade.create(&d, "VRS pipeline")?;
            if split {
                let motion = RawPipeline {
                    render_pass: self.motion_pass,
                    fragment: Some((self.modules[2], &motion_name)),
                    depth: (vk::CompareOp::GREATER, true),
                    rates: false,
                    ..shade
                };
                self.motion_prepass = motion.create(&d, "motion pre-pass pipeline")?;
            } else {
                let depth = RawPipeline {
                    fragment: None,
                    depth: (vk::CompareOp::GREATER, true),
                    color: ColorOut::None,
                    rates: false,
                    ..shade
                };
                self.depth_prepass = depth.create(&d, "depth pre-pass pipeline")?;
            }
        }
        Ok(())
    }

    /// The textured draws' layout (sets 0 and 1), modules and pipelines: shading (opaque and
    /// alpha-tested at EQUAL, blended at GREATER), and the pre-pass's opaque and alpha-tested
    /// draws (the alpha test at full rate).
    fn create_material_pipelines(&mut self, code: &[Vec<u32>], split: bool) -> Result<(), String> {
        let Some(sets) = &self.materials else {
            return Ok(());
        };
        let layouts = [self.set_layout, sets.layout];
        let stride = sets.vertex_stride;
        let d = self.device.clone();
        // SAFETY: create-infos outlive their calls; the set layouts are alive; each object is
        // stored in the pass as soon as it exists (destroyed in Drop).
        unsafe {
            self.material_layout = d
                .create_pipeline_layout(
                    &vk::PipelineLayoutCreateInfo::default().set_layouts(&layouts),
                    None,
                )
                .map_err(vk_err("material pipeline layout"))?;
            for (i, words) in code.iter().enumerate() {
                self.material_modules[i] = d
                    .create_shader_module(&vk::ShaderModuleCreateInfo::default().code(words), None)
                    .map_err(vk_err("material shader"))?;
            }
        }
        let names: Vec<std::ffi::CString> = MATERIAL_ENTRY_POINTS
            .iter()
            .map(|(_, e)| std::ffi::CString::new(*e).expect("entry names have no NUL"))
            .collect();
        let modules = self.material_modules;
        let module = |i: usize| (modules[i], names[i].as_c_str());
        let base = RawPipeline {
            layout: self.material_layout,
            render_pass: self.shade_pass,
            stride,
            attributes: &MATERIAL_ATTRIBUTES,
            vertex: module(0),
            fragment: Some(module(1)),
            depth: (vk::CompareOp::EQUAL, false),
            color: ColorOut::Write,
            rates: self.rated,
        };
        let blend = RawPipeline {
            depth: (vk::CompareOp::GREATER, false),
            color: ColorOut::Blend,
            ..base
        };
        let (prepass_opaque, prepass_mask) = if split {
            let opaque = RawPipeline {
                render_pass: self.motion_pass,
                fragment: Some(module(2)),
                depth: (vk::CompareOp::GREATER, true),
                rates: false,
                ..base
            };
            let mask = RawPipeline {
                fragment: Some(module(3)),
                ..opaque
            };
            (opaque, mask)
        } else {
            let opaque = RawPipeline {
                fragment: None,
                depth: (vk::CompareOp::GREATER, true),
                color: ColorOut::None,
                rates: false,
                ..base
            };
            let mask = RawPipeline {
                fragment: Some(module(4)),
                ..opaque
            };
            (opaque, mask)
        };
        // SAFETY: the modules, layout and render passes are alive; the shading-rate state is
        // chained only where the device has the extension.
        unsafe {
            self.material_shade[0] = base.create(&d, "material shading pipeline")?;
            self.material_shade[1] = blend.create(&d, "blended material pipeline")?;
            self.material_prepass[0] = prepass_opaque.create(&d, "material pre-pass pipeline")?;
            self.material_prepass[1] = prepass_mask.create(&d, "alpha-tested pre-pass pipeline")?;
        }
        Ok(())
    }

    /// A two-query pool of fragment-shader invocations (shading pass, motion pre-pass).
    fn create_statistics(&mut self) -> Result<(), String> {
        // SAFETY: pipelineStatisticsQuery is on when wgpu has PIPELINE_STATISTICS_QUERY (the
        // caller checks); the pool is stored in the pass at once.
        self.stats = unsafe {
            self.device.create_query_pool(
                &vk::QueryPoolCreateInfo::default()
                    .query_type(vk::QueryType::PIPELINE_STATISTICS)
                    .query_count(2)
                    .pipeline_statistics(
                        vk::QueryPipelineStatisticFlags::FRAGMENT_SHADER_INVOCATIONS,
                    ),
                None,
            )
        }
        .map_err(vk_err("statistics query pool"))?;
        Ok(())
    }
    /// The viewport (wgpu-hal's convention: flipped, negative height, so that clip space is
    /// WebGPU's, y up) and the render area.
    fn area(&self) -> (vk::Viewport, vk::Rect2D) {
        let [w, h] = self.size;
        let area = vk::Rect2D {
            offset: vk::Offset2D { x: 0, y: 0 },
            extent: vk::Extent2D {
                width: w,
                height: h,
            },
        };
        let viewport = vk::Viewport {
            x: 0.0,
            y: h as f32,
            width: w as f32,
            height: -(h as f32),
            min_depth: 0.0,
            max_depth: 1.0,
        };
        (viewport, area)
    }

    /// Records `body` into `encoder` between two full memory barriers (everything submitted
    /// before, then this, then everything after); false when the encoder is not Vulkan's.
    ///
    /// # Safety
    /// `encoder` must hold no wgpu commands (wgpu forbids mixing), and every handle `body`
    /// records must stay alive until the commands complete.
    unsafe fn record_raw(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        body: impl FnOnce(&ash::Device, vk::CommandBuffer),
    ) -> bool {
        let d = &self.device;
        let full_barrier = vk::MemoryBarrier::default()
            .src_access_mask(vk::AccessFlags::MEMORY_WRITE)
            .dst_access_mask(vk::AccessFlags::MEMORY_READ | vk::AccessFlags::MEMORY_WRITE);
        let all = vk::PipelineStageFlags::ALL_COMMANDS;
        // SAFETY: the caller's contract.
        unsafe {
            encoder.as_hal_mut::<Vulkan, _, _>(|e| {
                let Some(e) = e else { return false };
                let cb = e.raw_handle();
                let flags = vk::DependencyFlags::empty();
                d.cmd_pipeline_barrier(cb, all, all, flags, &[full_barrier], &[], &[]);
                body(d, cb);
                d.cmd_pipeline_barrier(cb, all, all, flags, &[full_barrier], &[], &[]);
                true
            })
        }
    }

    /// Binds the descriptor set, vertex and index buffers and draws every object with
    /// `pipeline`.
    ///
    /// # Safety
    /// Inside a render pass compatible with `pipeline`, on a command buffer being recorded.
    unsafe fn draw_scene(&self, d: &ash::Device, cb: vk::CommandBuffer, pipeline: vk::Pipeline) {
        // SAFETY: the caller's contract; the set, buffers and pipeline are alive.
        unsafe {
            d.cmd_bind_descriptor_sets(
                cb,
                vk::PipelineBindPoint::GRAPHICS,
                self.layout,
                0,
                &[self.set],
                &[],
            );
            d.cmd_bind_vertex_buffers(cb, 0, &[self.vertex], &[0]);
            d.cmd_bind_index_buffer(cb, self.index, 0, vk::IndexType::UINT32);
            d.cmd_bind_pipeline(cb, vk::PipelineBindPoint::GRAPHICS, pipeline);
            for (i, &(first, count, base)) in self.draws.iter().enumerate() {
                d.cmd_draw_indexed(cb, count, 1, first, base, i as u32);
            }
        }
    }

    /// Draws the textured models in `order` for `phase`: in the pre-pass opaque and alpha-tested
    /// draws (blended ones write no depth), in the shading pass every draw, blended ones last
    /// (`order` puts them there). An `order` that does not name the draws (none given) draws
    /// them in their own order.
    ///
    /// # Safety
    /// Inside a render pass compatible with the phase's pipelines, on a command buffer being
    /// recorded.
    unsafe fn draw_materials(
        &self,
        d: &ash::Device,
        cb: vk::CommandBuffer,
        phase: Phase,
        order: &[usize],
    ) {
        let Some(m) = &self.materials else { return };

        let own: Vec<usize>;
        let order = if order.len() == m.draws.len() {
            order
        } else {
            own = (0..m.draws.len()).collect();
            &own
        };
        let bind = vk::PipelineBindPoint::GRAPHICS;
        // SAFETY: the caller's contract; the sets, buffers and pipelines are alive.
        unsafe {
            d.cmd_bind_descriptor_sets(cb, bind, self.material_layout, 0, &[self.set], &[]);
            d.cmd_bind_vertex_buffers(cb, 0, &[m.vertex], &[0]);
            d.cmd_bind_index_buffer(cb, m.index, 0, vk::IndexType::UINT32);
            let mut current = vk::Pipeline::null();
            for &i in order {
                let Some(draw) = m.draws.get(i) else { continue };
                let pipeline = match (phase, draw.class) {
                    (Phase::Prepass, Class::Opaque) => self.material_prepass[0],
                    (Phase::Prepass, Class::Mask) => self.material_prepass[1],
                    (Phase::Prepass, Class::Blend) => continue,
                    (Phase::Shade, Class::Blend) => self.material_shade[1],
                    (Phase::Shade, _) => self.material_shade[0],
                };
                if pipeline != current {
                    d.cmd_bind_pipeline(cb, bind, pipeline);
                    current = pipeline;
                }
                let set = [m.sets[draw.material]];
                d.cmd_bind_descriptor_sets(cb, bind, self.material_layout, 1, &set, &[]);
                d.cmd_draw_indexed(
                    cb,
                    draw.index_count,
                    draw.object_count,
                    draw.first_index,
                    draw.base_vertex,
                    draw.first_object,
                );
            }
        }
    }

    /// Moves the textured draws' sampled textures into the state their descriptors say (see
    /// `raw_material.rs`), in a wgpu `encoder` submitted before the raw passes of this frame.
    pub fn transition_materials(&self, encoder: &mut wgpu::CommandEncoder) {
        if let Some(m) = &self.materials {
            m.transition(encoder);
        }
    }

    /// Whether the scene's textured draws include blended ones (drawn in the shading pass over
    /// the opaque surfaces: their invocations are beyond the shade-count model's covered pixels).
    pub fn has_blend(&self) -> bool {
        self.materials.as_ref().is_some_and(|m| m.has(Class::Blend))
    }

    /// The split shape's motion pre-pass for frame `parity` into `encoder` (which must hold
    /// nothing else): this frame's depth cleared and drawn, the motion written where it is
    /// drawn. Submit it after the encoder that moved the motion and depth targets into
    /// COLOR_TARGET / DEPTH_STENCIL_WRITE, before the rate pass. Does nothing in the single shape.
    /// `order` is this frame's order of the textured draws ([`MaterialGpu::draw_order`]).
    ///
    /// [`MaterialGpu::draw_order`]: crate::render::material::MaterialGpu::draw_order
    pub fn record_prepass(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        parity: usize,
        order: &[usize],
    ) {
        if self.motion_framebuffers.is_empty() {
            return;
        }
        let (viewport, area) = self.area();
        let clears = [
            vk::ClearValue::default(),
            vk::ClearValue {
                depth_stencil: vk::ClearDepthStencilValue {
                    depth: 0.0,
                    stencil: 0,
                },
            },
        ];
        let begin = vk::RenderPassBeginInfo::default()
            .render_pass(self.motion_pass)
            .framebuffer(self.motion_framebuffers[parity % self.motion_framebuffers.len()])
            .render_area(area)
            .clear_values(&clears);
        let subpass = vk::SubpassBeginInfo::default().contents(vk::SubpassContents::INLINE);
        let (stats, pipeline) = (self.stats, self.motion_prepass);
        // SAFETY: `encoder` holds no wgpu commands (the caller's contract); every handle is alive
        // while the pass is (kept clones of the wgpu objects, our own objects destroyed only in
        // Drop after the device is idle); the targets end in the layouts they began in.
        let ok = unsafe {
            self.record_raw(encoder, |d, cb| {
                d.cmd_reset_query_pool(cb, stats, PREPASS_QUERY, 1);
                d.cmd_begin_query(cb, stats, PREPASS_QUERY, vk::QueryControlFlags::empty());
                d.cmd_begin_render_pass2(cb, &begin, &subpass);
                d.cmd_set_viewport(cb, 0, &[viewport]);
                d.cmd_set_scissor(cb, 0, &[area]);
                self.draw_scene(d, cb, pipeline);
                self.draw_materials(d, cb, Phase::Prepass, order);
                d.cmd_end_render_pass2(cb, &vk::SubpassEndInfo::default());
                d.cmd_end_query(cb, stats, PREPASS_QUERY);
            })
        };
        self.recorded[PREPASS_QUERY as usize] |= ok;
    }

    /// The shading pass for frame `parity` into `encoder` (which must hold nothing else): the
    /// attachment bytes copied into the rate image, the colour cleared to `background`, then (in
    /// the single shape) the depth cleared and drawn by the depth pre-pass, and the shading draw
    /// at the attachment's rates. Submit it after the encoder that filled the staging buffer and
    /// moved the colour and depth targets into COLOR_TARGET / DEPTH_STENCIL_WRITE, before
    /// anything that reads the targets. The textured draws follow the untextured ones in
    /// `order` (this frame's: opaque, alpha-tested, blended back to front).
    pub fn record_shade(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        parity: usize,
        background: [f32; 4],
        order: &[usize],
    ) {
        let range = vk::ImageSubresourceRange {
            aspect_mask: vk::ImageAspectFlags::COLOR,
            base_mip_level: 0,
            level_count: 1,
            base_array_layer: 0,
            layer_count: 1,
        };
        let to_copy = vk::ImageMemoryBarrier::default()
            .src_access_mask(vk::AccessFlags::empty())
            .dst_access_mask(vk::AccessFlags::TRANSFER_WRITE)
            .old_layout(vk::ImageLayout::UNDEFINED)
            .new_layout(vk::ImageLayout::TRANSFER_DST_OPTIMAL)
            .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
            .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
            .image(self.rate_image)
            .subresource_range(range);
        let to_rate = to_copy
            .src_access_mask(vk::AccessFlags::TRANSFER_WRITE)
            .dst_access_mask(vk::AccessFlags::FRAGMENT_SHADING_RATE_ATTACHMENT_READ_KHR)
            .old_layout(vk::ImageLayout::TRANSFER_DST_OPTIMAL)
            .new_layout(vk::ImageLayout::FRAGMENT_SHADING_RATE_ATTACHMENT_OPTIMAL_KHR);
        let copy = vk::BufferImageCopy::default()
            .image_subresource(vk::ImageSubresourceLayers {
                aspect_mask: vk::ImageAspectFlags::COLOR,
                mip_level: 0,
                base_array_layer: 0,
                layer_count: 1,
            })
            .image_extent(vk::Extent3D {
                width: self.attachment_size[0],
                height: self.attachment_size[1],
                depth: 1,
            });
        let (viewport, area) = self.area();
        let clears = [
            vk::ClearValue {
                color: vk::ClearColorValue {
                    float32: background,
                },
            },
            vk::ClearValue {
                depth_stencil: vk::ClearDepthStencilValue {
                    depth: 0.0,
                    stencil: 0,
                },
            },
        ];
        let begin = vk::RenderPassBeginInfo::default()
            .render_pass(self.shade_pass)
            .framebuffer(self.shade_framebuffers[parity % self.shade_framebuffers.len()])
            .render_area(area)
            .clear_values(&clears);
        let subpass = vk::SubpassBeginInfo::default().contents(vk::SubpassContents::INLINE);
        let (stats, pipeline, depth_prepass) = (self.stats, self.pipeline, self.depth_prepass);
        let (staging, rate_image, rated) = (self.staging, self.rate_image, self.rated);
        // SAFETY: as in `record_prepass`; the rate image is ours and goes from UNDEFINED (its
        // bytes are rewritten whole) through TRANSFER_DST to the attachment layout each frame.
        let ok = unsafe {
            self.record_raw(encoder, |d, cb| {
                if rated {
                    d.cmd_pipeline_barrier(
                        cb,
                        vk::PipelineStageFlags::TOP_OF_PIPE,
                        vk::PipelineStageFlags::TRANSFER,
                        vk::DependencyFlags::empty(),
                        &[],
                        &[],
                        &[to_copy],
                    );
                    d.cmd_copy_buffer_to_image(
                        cb,
                        staging,
                        rate_image,
                        vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                        &[copy],
                    );
                    d.cmd_pipeline_barrier(
                        cb,
                        vk::PipelineStageFlags::TRANSFER,
                        vk::PipelineStageFlags::FRAGMENT_SHADING_RATE_ATTACHMENT_KHR,
                        vk::DependencyFlags::empty(),
                        &[],
                        &[],
                        &[to_rate],
                    );
                }
                d.cmd_reset_query_pool(cb, stats, SHADE_QUERY, 1);
                d.cmd_begin_query(cb, stats, SHADE_QUERY, vk::QueryControlFlags::empty());
                d.cmd_begin_render_pass2(cb, &begin, &subpass);
                d.cmd_set_viewport(cb, 0, &[viewport]);
                d.cmd_set_scissor(cb, 0, &[area]);
                if depth_prepass != vk::Pipeline::null() {
                    self.draw_scene(d, cb, depth_prepass);
                    self.draw_materials(d, cb, Phase::Prepass, order);
                }
                self.draw_scene(d, cb, pipeline);
                self.draw_materials(d, cb, Phase::Shade, order);
                d.cmd_end_render_pass2(cb, &vk::SubpassEndInfo::default());
                d.cmd_end_query(cb, stats, SHADE_QUERY);
            })
        };
        self.recorded[SHADE_QUERY as usize] |= ok;
    }

    /// Fragment-shader invocations of the last recorded shading pass and motion pre-pass (`None`
    /// in the single shape), once its frame has completed; `None` before any pass or while the
    /// result is not available.
    pub fn invocations(&self) -> (Option<u64>, Option<u64>) {
        let read = |query: u32| {
            if !self.recorded[query as usize] {
                return None;
            }
            let mut out = [0u64; 1];
            // SAFETY: the query was begun and ended in a recorded pass; no WAIT flag, so a query
            // still in flight returns NOT_READY (an error here) rather than blocking.
            unsafe {
                self.device.get_query_pool_results(
                    self.stats,
                    query,
                    &mut out,
                    vk::QueryResultFlags::TYPE_64,
                )
            }
            .ok()
            .map(|_| out[0])
        };
        (read(SHADE_QUERY), read(PREPASS_QUERY))
    }
}

impl Drop for RawVrsPass {
    fn drop(&mut self) {
        let d = &self.device;
        // SAFETY: waiting for the device to be idle first means no submitted command buffer
        // still uses these objects; each was created on `d` by `new` (null handles, from a `new`
        // that failed part-way or of the other shape, are ignored by the destroy calls).
        unsafe {
            let _ = d.device_wait_idle();
            d.destroy_query_pool(self.stats, None);
            for p in [self.pipeline, self.depth_prepass, self.motion_prepass] {
                d.destroy_pipeline(p, None);
            }
            for p in self.material_shade.into_iter().chain(self.material_prepass) {
                d.destroy_pipeline(p, None);
            }
            for m in self.modules.into_iter().chain(self.material_modules) {
                d.destroy_shader_module(m, None);
            }
            d.destroy_pipeline_layout(self.layout, None);
            d.destroy_pipeline_layout(self.material_layout, None);
            // The material sets and samplers are `self.materials`' own (its Drop, after this).
            d.destroy_descriptor_pool(self.pool, None);
            d.destroy_descriptor_set_layout(self.set_layout, None);
            for &fb in self
                .shade_framebuffers
                .iter()
                .chain(&self.motion_framebuffers)
            {
                d.destroy_framebuffer(fb, None);
            }
            d.destroy_render_pass(self.shade_pass, None);
            d.destroy_render_pass(self.motion_pass, None);
            for &v in &self.views {
                d.destroy_image_view(v, None);
            }
            d.destroy_image(self.rate_image, None);
            d.free_memory(self.rate_memory, None);
        }
    }
}
