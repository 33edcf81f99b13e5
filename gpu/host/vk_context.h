/* The smallest Vulkan a compute host needs: one device with shaderFloat64 and a compute queue,
 * host-visible storage buffers, compute pipelines from SPIR-V with one descriptor set of storage
 * buffers and push constants, one command buffer at a time, timestamps. Used by gpu/host's DLS
 * apply and reference samplers (prefix gpu_). Not part of liblbk: liblbk stays dependency-free.
 *
 * Device choice: LBK_GPU_DEVICE=<index or name substring> picks one; otherwise the first device
 * with shaderFloat64 and a compute queue (the loader finds lavapipe, or set VK_ICD_FILENAMES).
 *
 * Thread safety: a context is used by one thread at a time. */
#ifndef LBK_GPU_VK_CONTEXT_H
#define LBK_GPU_VK_CONTEXT_H

#include <stddef.h>
#include <stdint.h>
#include <vulkan/vulkan.h>

typedef struct gpu_ctx {
    VkInstance instance;
    VkPhysicalDevice phys;
    VkDevice dev;
    VkQueue queue;
    uint32_t queue_family;
    VkCommandPool pool;
    VkCommandBuffer cmd;
    VkFence fence;
    VkQueryPool timestamps; /* VK_NULL_HANDLE when the queue has no timestamps */
    double timestamp_ns;    /* nanoseconds per tick */
    VkPhysicalDeviceMemoryProperties mem;
    VkDeviceSize max_storage_range;
    uint32_t max_groups_x;
    char device_name[VK_MAX_PHYSICAL_DEVICE_NAME_SIZE];
    int cpu_device; /* VK_PHYSICAL_DEVICE_TYPE_CPU: lavapipe and the like */
    int buffers_device_local; /* the last buffer created is in device-local memory (resizable BAR) */
} gpu_ctx;

/* 0: ready; 1: no usable device (Vulkan missing, no ICD, no shaderFloat64): a test skips;
 * -1: an error. err gets the reason in both non-zero cases. */
int gpu_open(gpu_ctx *c, char *err, size_t err_len);
void gpu_close(gpu_ctx *c);
/* Everything but the instance: a process that keeps the instance until it exits keeps the driver
 * loaded, so that LeakSanitizer still sees the driver's static allocations as reachable (the
 * loader unloads the driver when the instance goes). */
void gpu_close_device(gpu_ctx *c);

typedef struct gpu_buffer {
    VkBuffer buf;
    VkDeviceMemory mem;
    void *map; /* host-visible, coherent, mapped for the buffer's life */
    VkDeviceSize size;
} gpu_buffer;

/* A storage buffer (also a transfer source and destination) of at least `size` bytes (rounded up
 * to 16, at least 16), optionally filled with `data` (the rest zero). 0 on success. */
int gpu_buffer_create(gpu_ctx *c, VkDeviceSize size, const void *data, gpu_buffer *b);
void gpu_buffer_destroy(gpu_ctx *c, gpu_buffer *b);

typedef struct gpu_pipeline {
    VkShaderModule module;
    VkDescriptorSetLayout set_layout;
    VkPipelineLayout layout;
    VkPipeline pipeline;
    VkDescriptorPool pool;
    VkDescriptorSet set;
    uint32_t bindings, push_size;
} gpu_pipeline;

/* A compute pipeline over `bindings` storage buffers (bindings 0..n-1) and `push_size` bytes of
 * push constants. 0 on success. */
int gpu_pipeline_create(gpu_ctx *c, const uint32_t *spirv, size_t spirv_bytes, uint32_t bindings, uint32_t push_size,
                        gpu_pipeline *p);
/* Points binding i at buffers[i] (whole buffer). */
void gpu_pipeline_bind(gpu_ctx *c, gpu_pipeline *p, const gpu_buffer *const *buffers);
void gpu_pipeline_destroy(gpu_ctx *c, gpu_pipeline *p);

/* Recording: begin, then vkCmd* on c->cmd, then submit (waits for completion). 0 on success. */
int gpu_begin(gpu_ctx *c);
int gpu_submit(gpu_ctx *c);
/* Binds the pipeline and its set, pushes `push`, dispatches ceil(invocations / 64) groups of 64
 * (spread over y when they pass maxComputeWorkGroupCount[0]). */
void gpu_dispatch(gpu_ctx *c, const gpu_pipeline *p, const void *push, uint64_t invocations);
/* A full memory barrier between the commands before and after (compute and transfer). */
void gpu_barrier(gpu_ctx *c);
/* Timestamps 0 and 1 around the commands of one submission; gpu_elapsed_ms after submit (−1 when the
 * queue has none). */
void gpu_timestamp(gpu_ctx *c, uint32_t index);
double gpu_elapsed_ms(gpu_ctx *c);

#endif
