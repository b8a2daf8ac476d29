//! One raw Vulkan graphics pipeline of the hardware path (`raw_pass.rs`): the fixed-function
//! state every raw pipeline shares, built in one place. Triangles, no culling, one sample,
//! dynamic viewport and scissor, as wgpu builds the scene's and `material.rs`'s pipelines; what
//! differs between the passes' pipelines (vertex layout, shaders, depth test, colour output,
//! whether the attachment decides the fragment size) is a field of [`RawPipeline`].

use ash::vk;

/// What a draw writes to the colour attachment.
#[derive(Clone, Copy)]
pub(super) enum ColorOut {
    /// Nothing (write mask 0): `native-vrs`'s depth pre-pass.
    None,
    /// Every channel, no blending.
    Write,
    /// glTF BLEND: wgpu's `BlendState::ALPHA_BLENDING` (colour `src_alpha`, `1 - src_alpha`;
    /// alpha `1`, `1 - src_alpha`), what `material.rs`'s blended pipeline uses.
    Blend,
}

/// A shader stage's module and entry point.
pub(super) type Stage<'a> = (vk::ShaderModule, &'a std::ffi::CStr);

/// One pipeline: its layout and render pass, the vertex buffer's stride and attributes (format,
/// offset; location = index), its shaders, depth test and colour output.
#[derive(Clone, Copy)]
pub(super) struct RawPipeline<'a> {
    pub layout: vk::PipelineLayout,
    pub render_pass: vk::RenderPass,
    pub stride: u32,
    pub attributes: &'a [(vk::Format, u32)],
    pub vertex: Stage<'a>,
    pub fragment: Option<Stage<'a>>,
    /// Depth compare op and whether depth is written.
    pub depth: (vk::CompareOp, bool),
    pub color: ColorOut,
    /// Whether the attachment decides the fragment size (the shading draws on a device with
    /// the extension): [`attachment_rates`].
    pub rates: bool,
}

/// The shading pipelines' rate state: 1x1 from the pipeline, the attachment's rate replacing it
/// (combiner ops KEEP, REPLACE): the attachment alone decides the rate.
fn attachment_rates() -> vk::PipelineFragmentShadingRateStateCreateInfoKHR<'static> {
    vk::PipelineFragmentShadingRateStateCreateInfoKHR::default()
        .fragment_size(vk::Extent2D {
            width: 1,
            height: 1,
        })
        .combiner_ops([
            vk::FragmentShadingRateCombinerOpKHR::KEEP,
            vk::FragmentShadingRateCombinerOpKHR::REPLACE,
        ])
}

fn stage<'a>(
    flags: vk::ShaderStageFlags,
    (module, name): Stage<'a>,
) -> vk::PipelineShaderStageCreateInfo<'a> {
    vk::PipelineShaderStageCreateInfo::default()
        .stage(flags)
        .module(module)
        .name(name)
}

fn blend_attachment(color: ColorOut) -> vk::PipelineColorBlendAttachmentState {
    match color {
        ColorOut::None => vk::PipelineColorBlendAttachmentState::default(),
        ColorOut::Write => vk::PipelineColorBlendAttachmentState::default()
            .color_write_mask(vk::ColorComponentFlags::RGBA),
        ColorOut::Blend => vk::PipelineColorBlendAttachmentState::default()
            .blend_enable(true)
            .src_color_blend_factor(vk::BlendFactor::SRC_ALPHA)
            .dst_color_blend_factor(vk::BlendFactor::ONE_MINUS_SRC_ALPHA)
            .color_blend_op(vk::BlendOp::ADD)
            .src_alpha_blend_factor(vk::BlendFactor::ONE)
            .dst_alpha_blend_factor(vk::BlendFactor::ONE_MINUS_SRC_ALPHA)
            .alpha_blend_op(vk::BlendOp::ADD)
            .color_write_mask(vk::ColorComponentFlags::RGBA),
    }
}

impl RawPipeline<'_> {
    /// # Safety
    /// The modules, layout and render pass are alive on `d`; `rates` only where the device has
    /// VK_KHR_fragment_shading_rate turned on.
    pub unsafe fn create(&self, d: &ash::Device, what: &str) -> Result<vk::Pipeline, String> {
        let mut stages = vec![stage(vk::ShaderStageFlags::VERTEX, self.vertex)];
        if let Some(fragment) = self.fragment {
            stages.push(stage(vk::ShaderStageFlags::FRAGMENT, fragment));
        }
        let bindings = [vk::VertexInputBindingDescription {
            binding: 0,
            stride: self.stride,
            input_rate: vk::VertexInputRate::VERTEX,
        }];
        let attributes: Vec<vk::VertexInputAttributeDescription> = self
            .attributes
            .iter()
            .enumerate()
            .map(
                |(i, &(format, offset))| vk::VertexInputAttributeDescription {
                    location: i as u32,
                    binding: 0,
                    format,
                    offset,
                },
            )
            .collect();
        let vertex_input = vk::PipelineVertexInputStateCreateInfo::default()
            .vertex_binding_descriptions(&bindings)
            .vertex_attribute_descriptions(&attributes);
        let assembly = vk::PipelineInputAssemblyStateCreateInfo::default()
            .topology(vk::PrimitiveTopology::TRIANGLE_LIST);
        let viewport = vk::PipelineViewportStateCreateInfo::default()
            .viewport_count(1)
            .scissor_count(1);
        let raster = vk::PipelineRasterizationStateCreateInfo::default()
            .polygon_mode(vk::PolygonMode::FILL)
            .cull_mode(vk::CullModeFlags::NONE)
            .front_face(vk::FrontFace::COUNTER_CLOCKWISE)
            .line_width(1.0);
        let multisample = vk::PipelineMultisampleStateCreateInfo::default()
            .rasterization_samples(vk::SampleCountFlags::TYPE_1);
        let depth = vk::PipelineDepthStencilStateCreateInfo::default()
            .depth_test_enable(true)
            .depth_write_enable(self.depth.1)
            .depth_compare_op(self.depth.0);
        let attachments = [blend_attachment(self.color)];
        let blend = vk::PipelineColorBlendStateCreateInfo::default().attachments(&attachments);
        let dynamic_states = [vk::DynamicState::VIEWPORT, vk::DynamicState::SCISSOR];
        let dynamic = vk::PipelineDynamicStateCreateInfo::default().dynamic_states(&dynamic_states);
        let mut rate_state = attachment_rates();
        let info = vk::GraphicsPipelineCreateInfo::default()
            .stages(&stages)
            .vertex_input_state(&vertex_input)
            .input_assembly_state(&assembly)
            .viewport_state(&viewport)
            .rasterization_state(&raster)
            .multisample_state(&multisample)
            .depth_stencil_state(&depth)
            .color_blend_state(&blend)
            .dynamic_state(&dynamic)
            .layout(self.layout)
            .render_pass(self.render_pass)
            .subpass(0);
        let info = if self.rates {
            info.push_next(&mut rate_state)
        } else {
            info
        };
        // SAFETY: every state struct and the shading-rate chain live across the call; the
        // caller's contract covers the modules, layout and render pass.
        unsafe { d.create_graphics_pipelines(vk::PipelineCache::null(), &[info], None) }
            .map(|p| p[0])
            .map_err(|(_, e)| format!("{what}: {e}"))
    }
}
