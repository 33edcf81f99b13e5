/* Minimal Vulkan compute context (vk_context.h). */
#include "gpu/host/vk_context.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define GROUP 64u

static int fail(char *err, size_t n, int code, const char *what, VkResult r)
{
    if (err && n) snprintf(err, n, "%s (VkResult %d)", what, (int)r);
    return code;
}

/* The device LBK_GPU_DEVICE names (index or name substring), else the first usable one. */
static int pick_device(gpu_ctx *c, char *err, size_t n)
{
    uint32_t count = 0;
    VkResult r = vkEnumeratePhysicalDevices(c->instance, &count, NULL);
    if (r != VK_SUCCESS || count == 0) return fail(err, n, 1, "no Vulkan device", r);
    VkPhysicalDevice *devs = calloc(count, sizeof *devs);
    if (!devs) return fail(err, n, -1, "out of memory", VK_ERROR_OUT_OF_HOST_MEMORY);
    vkEnumeratePhysicalDevices(c->instance, &count, devs);
    const char *want = getenv("LBK_GPU_DEVICE");
    int found = 0;
    for (uint32_t i = 0; i < count && !found; i++) {
        VkPhysicalDeviceProperties pr;
        VkPhysicalDeviceFeatures f;
        vkGetPhysicalDeviceProperties(devs[i], &pr);
        vkGetPhysicalDeviceFeatures(devs[i], &f);
        if (want && *want) {
            char idx[16];
            snprintf(idx, sizeof idx, "%u", i);
            if (strcmp(want, idx) && !strstr(pr.deviceName, want)) continue;
        }
        if (!f.shaderFloat64) continue;
        uint32_t qn = 0;
        vkGetPhysicalDeviceQueueFamilyProperties(devs[i], &qn, NULL);
        VkQueueFamilyProperties *q = calloc(qn ? qn : 1, sizeof *q);
        if (!q) break;
        vkGetPhysicalDeviceQueueFamilyProperties(devs[i], &qn, q);
        for (uint32_t k = 0; k < qn; k++)
            if (q[k].queueFlags & VK_QUEUE_COMPUTE_BIT) {
                c->phys = devs[i];
                c->queue_family = k;
                c->timestamp_ns = q[k].timestampValidBits ? pr.limits.timestampPeriod : 0.0;
                c->max_storage_range = pr.limits.maxStorageBufferRange;
                c->max_groups_x = pr.limits.maxComputeWorkGroupCount[0];
                c->cpu_device = pr.deviceType == VK_PHYSICAL_DEVICE_TYPE_CPU;
                snprintf(c->device_name, sizeof c->device_name, "%s", pr.deviceName);
                found = 1;
                break;
            }
        free(q);
    }
    free(devs);
    return found ? 0 : fail(err, n, 1, "no Vulkan device with shaderFloat64 and a compute queue", VK_SUCCESS);
}

int gpu_open(gpu_ctx *c, char *err, size_t n)
{
    memset(c, 0, sizeof *c);
    VkApplicationInfo app = {.sType = VK_STRUCTURE_TYPE_APPLICATION_INFO, .pApplicationName = "lbk-gpu",
                             .apiVersion = VK_API_VERSION_1_1};
    VkInstanceCreateInfo ici = {.sType = VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO, .pApplicationInfo = &app};
    VkResult r = vkCreateInstance(&ici, NULL, &c->instance);
    if (r != VK_SUCCESS) return fail(err, n, 1, "no Vulkan instance (is an ICD installed? mesa-vulkan-drivers)", r);
    int p = pick_device(c, err, n);
    if (p) {
        gpu_close(c);
        return p;
    }
    const float prio = 1.0f;
    VkDeviceQueueCreateInfo qci = {.sType = VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO, .queueFamilyIndex = c->queue_family,
                                   .queueCount = 1, .pQueuePriorities = &prio};
    VkPhysicalDeviceFeatures feat = {.shaderFloat64 = VK_TRUE};
    VkDeviceCreateInfo dci = {.sType = VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO, .queueCreateInfoCount = 1,
                              .pQueueCreateInfos = &qci, .pEnabledFeatures = &feat};
    if ((r = vkCreateDevice(c->phys, &dci, NULL, &c->dev)) != VK_SUCCESS) {
        gpu_close(c);
        return fail(err, n, -1, "vkCreateDevice", r);
    }
    vkGetDeviceQueue(c->dev, c->queue_family, 0, &c->queue);
    vkGetPhysicalDeviceMemoryProperties(c->phys, &c->mem);
    VkCommandPoolCreateInfo pci = {.sType = VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO,
                                   .flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT, .queueFamilyIndex = c->queue_family};
    VkFenceCreateInfo fci = {.sType = VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
    r = vkCreateCommandPool(c->dev, &pci, NULL, &c->pool);
    if (r == VK_SUCCESS) {
        VkCommandBufferAllocateInfo ai = {.sType = VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO, .commandPool = c->pool,
                                          .level = VK_COMMAND_BUFFER_LEVEL_PRIMARY, .commandBufferCount = 1};
        r = vkAllocateCommandBuffers(c->dev, &ai, &c->cmd);
    }
    if (r == VK_SUCCESS) r = vkCreateFence(c->dev, &fci, NULL, &c->fence);
    if (r == VK_SUCCESS && c->timestamp_ns > 0.0) {
        VkQueryPoolCreateInfo qp = {.sType = VK_STRUCTURE_TYPE_QUERY_POOL_CREATE_INFO, .queryType = VK_QUERY_TYPE_TIMESTAMP,
                                    .queryCount = 2};
        if (vkCreateQueryPool(c->dev, &qp, NULL, &c->timestamps) != VK_SUCCESS) c->timestamps = VK_NULL_HANDLE;
    }
    if (r != VK_SUCCESS) {
        gpu_close(c);
        return fail(err, n, -1, "command pool, buffer or fence", r);
    }
    return 0;
}

void gpu_close_device(gpu_ctx *c)
{
    if (c->dev) {
        vkDeviceWaitIdle(c->dev);
        if (c->timestamps) vkDestroyQueryPool(c->dev, c->timestamps, NULL);
        if (c->fence) vkDestroyFence(c->dev, c->fence, NULL);
        if (c->pool) vkDestroyCommandPool(c->dev, c->pool, NULL);
        vkDestroyDevice(c->dev, NULL);
    }
    c->dev = VK_NULL_HANDLE, c->timestamps = VK_NULL_HANDLE, c->fence = VK_NULL_HANDLE, c->pool = VK_NULL_HANDLE;
}

void gpu_close(gpu_ctx *c)
{
    gpu_close_device(c);
    if (c->instance) vkDestroyInstance(c->instance, NULL);
    memset(c, 0, sizeof *c);
}

static int memory_type(const gpu_ctx *c, uint32_t bits)
{
    const VkMemoryPropertyFlags need = VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT;
    int any = -1;
    for (uint32_t i = 0; i < c->mem.memoryTypeCount; i++) {
        if (!(bits & (1u << i)) || (c->mem.memoryTypes[i].propertyFlags & need) != need) continue;
        if (c->mem.memoryTypes[i].propertyFlags & VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT) return (int)i; /* resizable BAR */
        if (any < 0) any = (int)i;
    }
    return any;
}

int gpu_buffer_create(gpu_ctx *c, VkDeviceSize size, const void *data, gpu_buffer *b)
{
    memset(b, 0, sizeof *b);
    const VkDeviceSize alloc = size < 16 ? 16 : (size + 15) & ~(VkDeviceSize)15;
    VkBufferCreateInfo bi = {.sType = VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO, .size = alloc,
                             .usage = VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_SRC_BIT |
                                      VK_BUFFER_USAGE_TRANSFER_DST_BIT,
                             .sharingMode = VK_SHARING_MODE_EXCLUSIVE};
    if (vkCreateBuffer(c->dev, &bi, NULL, &b->buf) != VK_SUCCESS) return -1;
    VkMemoryRequirements req;
    vkGetBufferMemoryRequirements(c->dev, b->buf, &req);
    const int type = memory_type(c, req.memoryTypeBits);
    VkMemoryAllocateInfo ai = {.sType = VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO, .allocationSize = req.size,
                               .memoryTypeIndex = (uint32_t)type};
    if (type < 0 || vkAllocateMemory(c->dev, &ai, NULL, &b->mem) != VK_SUCCESS ||
        vkBindBufferMemory(c->dev, b->buf, b->mem, 0) != VK_SUCCESS ||
        vkMapMemory(c->dev, b->mem, 0, VK_WHOLE_SIZE, 0, &b->map) != VK_SUCCESS) {
        gpu_buffer_destroy(c, b);
        return -1;
    }
    b->size = alloc;
    c->buffers_device_local = (c->mem.memoryTypes[type].propertyFlags & VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT) != 0;
    memset(b->map, 0, alloc);
    if (data && size) memcpy(b->map, data, size);
    return 0;
}

void gpu_buffer_destroy(gpu_ctx *c, gpu_buffer *b)
{
    if (b->buf) vkDestroyBuffer(c->dev, b->buf, NULL);
    if (b->mem) vkFreeMemory(c->dev, b->mem, NULL);
    memset(b, 0, sizeof *b);
}

int gpu_pipeline_create(gpu_ctx *c, const uint32_t *spirv, size_t bytes, uint32_t bindings, uint32_t push_size,
                        gpu_pipeline *p)
{
    memset(p, 0, sizeof *p);
    p->bindings = bindings, p->push_size = push_size;
    VkShaderModuleCreateInfo mi = {.sType = VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO, .codeSize = bytes, .pCode = spirv};
    VkDescriptorSetLayoutBinding lb[16];
    if (bindings > 16) return -1;
    for (uint32_t i = 0; i < bindings; i++)
        lb[i] = (VkDescriptorSetLayoutBinding){.binding = i, .descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER,
                                               .descriptorCount = 1, .stageFlags = VK_SHADER_STAGE_COMPUTE_BIT};
    VkDescriptorSetLayoutCreateInfo li = {.sType = VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO,
                                          .bindingCount = bindings, .pBindings = lb};
    VkPushConstantRange pr = {.stageFlags = VK_SHADER_STAGE_COMPUTE_BIT, .size = push_size};
    VkPipelineLayoutCreateInfo pli = {.sType = VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO, .setLayoutCount = 1,
                                      .pushConstantRangeCount = push_size ? 1 : 0, .pPushConstantRanges = &pr};
    VkDescriptorPoolSize ps = {.type = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, .descriptorCount = bindings};
    VkDescriptorPoolCreateInfo dpi = {.sType = VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO, .maxSets = 1,
                                      .poolSizeCount = 1, .pPoolSizes = &ps};
    if (vkCreateShaderModule(c->dev, &mi, NULL, &p->module) != VK_SUCCESS) return -1;
    pli.pSetLayouts = &p->set_layout;
    if (vkCreateDescriptorSetLayout(c->dev, &li, NULL, &p->set_layout) != VK_SUCCESS ||
        vkCreatePipelineLayout(c->dev, &pli, NULL, &p->layout) != VK_SUCCESS ||
        vkCreateDescriptorPool(c->dev, &dpi, NULL, &p->pool) != VK_SUCCESS) {
        gpu_pipeline_destroy(c, p);
        return -1;
    }
    VkDescriptorSetAllocateInfo ai = {.sType = VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO, .descriptorPool = p->pool,
                                      .descriptorSetCount = 1, .pSetLayouts = &p->set_layout};
    VkComputePipelineCreateInfo ci = {.sType = VK_STRUCTURE_TYPE_COMPUTE_PIPELINE_CREATE_INFO,
                                      .stage = {.sType = VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO,
                                                .stage = VK_SHADER_STAGE_COMPUTE_BIT, .module = p->module, .pName = "main"},
                                      .layout = p->layout};
    if (vkAllocateDescriptorSets(c->dev, &ai, &p->set) != VK_SUCCESS ||
        vkCreateComputePipelines(c->dev, VK_NULL_HANDLE, 1, &ci, NULL, &p->pipeline) != VK_SUCCESS) {
        gpu_pipeline_destroy(c, p);
        return -1;
    }
    return 0;
}

void gpu_pipeline_bind(gpu_ctx *c, gpu_pipeline *p, const gpu_buffer *const *buffers)
{
    VkDescriptorBufferInfo bi[16];
    VkWriteDescriptorSet w[16];
    for (uint32_t i = 0; i < p->bindings; i++) {
        bi[i] = (VkDescriptorBufferInfo){.buffer = buffers[i]->buf, .range = VK_WHOLE_SIZE};
        w[i] = (VkWriteDescriptorSet){.sType = VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET, .dstSet = p->set, .dstBinding = i,
                                      .descriptorCount = 1, .descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER,
                                      .pBufferInfo = &bi[i]};
    }
    vkUpdateDescriptorSets(c->dev, p->bindings, w, 0, NULL);
}

void gpu_pipeline_destroy(gpu_ctx *c, gpu_pipeline *p)
{
    if (p->pipeline) vkDestroyPipeline(c->dev, p->pipeline, NULL);
    if (p->pool) vkDestroyDescriptorPool(c->dev, p->pool, NULL);
    if (p->layout) vkDestroyPipelineLayout(c->dev, p->layout, NULL);
    if (p->set_layout) vkDestroyDescriptorSetLayout(c->dev, p->set_layout, NULL);
    if (p->module) vkDestroyShaderModule(c->dev, p->module, NULL);
    memset(p, 0, sizeof *p);
}

int gpu_begin(gpu_ctx *c)
{
    VkCommandBufferBeginInfo bi = {.sType = VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO,
                                   .flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT};
    if (vkResetCommandBuffer(c->cmd, 0) != VK_SUCCESS || vkBeginCommandBuffer(c->cmd, &bi) != VK_SUCCESS) return -1;
    if (c->timestamps) vkCmdResetQueryPool(c->cmd, c->timestamps, 0, 2);
    return 0;
}

int gpu_submit(gpu_ctx *c)
{
    if (vkEndCommandBuffer(c->cmd) != VK_SUCCESS) return -1;
    VkSubmitInfo si = {.sType = VK_STRUCTURE_TYPE_SUBMIT_INFO, .commandBufferCount = 1, .pCommandBuffers = &c->cmd};
    if (vkResetFences(c->dev, 1, &c->fence) != VK_SUCCESS || vkQueueSubmit(c->queue, 1, &si, c->fence) != VK_SUCCESS)
        return -1;
    return vkWaitForFences(c->dev, 1, &c->fence, VK_TRUE, UINT64_MAX) == VK_SUCCESS ? 0 : -1;
}

void gpu_dispatch(gpu_ctx *c, const gpu_pipeline *p, const void *push, uint64_t invocations)
{
    const uint64_t groups = (invocations + GROUP - 1) / GROUP;
    if (groups == 0) return;
    const uint64_t max_x = c->max_groups_x ? c->max_groups_x : 65535;
    const uint32_t gx = (uint32_t)(groups < max_x ? groups : max_x), gy = (uint32_t)((groups + gx - 1) / gx);
    vkCmdBindPipeline(c->cmd, VK_PIPELINE_BIND_POINT_COMPUTE, p->pipeline);
    vkCmdBindDescriptorSets(c->cmd, VK_PIPELINE_BIND_POINT_COMPUTE, p->layout, 0, 1, &p->set, 0, NULL);
    if (p->push_size) vkCmdPushConstants(c->cmd, p->layout, VK_SHADER_STAGE_COMPUTE_BIT, 0, p->push_size, push);
    vkCmdDispatch(c->cmd, gx, gy, 1);
}

void gpu_barrier(gpu_ctx *c)
{
    VkMemoryBarrier mb = {.sType = VK_STRUCTURE_TYPE_MEMORY_BARRIER,
                          .srcAccessMask = VK_ACCESS_SHADER_WRITE_BIT | VK_ACCESS_TRANSFER_WRITE_BIT,
                          .dstAccessMask = VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_SHADER_WRITE_BIT | VK_ACCESS_TRANSFER_READ_BIT |
                                           VK_ACCESS_TRANSFER_WRITE_BIT | VK_ACCESS_HOST_READ_BIT};
    vkCmdPipelineBarrier(c->cmd, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT | VK_PIPELINE_STAGE_TRANSFER_BIT,
                         VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT | VK_PIPELINE_STAGE_TRANSFER_BIT | VK_PIPELINE_STAGE_HOST_BIT, 0, 1,
                         &mb, 0, NULL, 0, NULL);
}

void gpu_timestamp(gpu_ctx *c, uint32_t index)
{
    if (c->timestamps)
        vkCmdWriteTimestamp(c->cmd, index ? VK_PIPELINE_STAGE_BOTTOM_OF_PIPE_BIT : VK_PIPELINE_STAGE_TOP_OF_PIPE_BIT,
                            c->timestamps, index);
}

double gpu_elapsed_ms(gpu_ctx *c)
{
    uint64_t t[2];
    if (!c->timestamps || vkGetQueryPoolResults(c->dev, c->timestamps, 0, 2, sizeof t, t, sizeof t[0],
                                                VK_QUERY_RESULT_64_BIT | VK_QUERY_RESULT_WAIT_BIT) != VK_SUCCESS)
        return -1.0;
    return (double)(t[1] - t[0]) * c->timestamp_ns * 1e-6;
}
