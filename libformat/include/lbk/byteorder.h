/* Little-endian access to bytes (every lbk file is little-endian whatever the host is), shared by
 * liblbk, the baker (parts, bake/dist) and tools: header-only, inline, no symbols. */
#ifndef LBK_BYTEORDER_H
#define LBK_BYTEORDER_H

#include <stdint.h>
#include <string.h>

static inline uint16_t lbk_rd16(const uint8_t *p) { return (uint16_t)(p[0] | (p[1] << 8)); }
static inline uint32_t lbk_rd32(const uint8_t *p)
{
    return (uint32_t)p[0] | ((uint32_t)p[1] << 8) | ((uint32_t)p[2] << 16) | ((uint32_t)p[3] << 24);
}
static inline uint64_t lbk_rd64(const uint8_t *p) { return (uint64_t)lbk_rd32(p) | ((uint64_t)lbk_rd32(p + 4) << 32); }
static inline float lbk_rdf32(const uint8_t *p)
{
    uint32_t u = lbk_rd32(p);
    float f;
    memcpy(&f, &u, 4);
    return f;
}
static inline double lbk_rdf64(const uint8_t *p)
{
    uint64_t u = lbk_rd64(p);
    double d;
    memcpy(&d, &u, 8);
    return d;
}
static inline void lbk_wr16(uint8_t *p, uint16_t v) { p[0] = (uint8_t)v; p[1] = (uint8_t)(v >> 8); }
static inline void lbk_wr32(uint8_t *p, uint32_t v)
{
    p[0] = (uint8_t)v; p[1] = (uint8_t)(v >> 8); p[2] = (uint8_t)(v >> 16); p[3] = (uint8_t)(v >> 24);
}
static inline void lbk_wr64(uint8_t *p, uint64_t v) { lbk_wr32(p, (uint32_t)v); lbk_wr32(p + 4, (uint32_t)(v >> 32)); }
static inline void lbk_wrf32(uint8_t *p, float f)
{
    uint32_t u;
    memcpy(&u, &f, 4);
    lbk_wr32(p, u);
}
static inline void lbk_wrf64(uint8_t *p, double d)
{
    uint64_t u;
    memcpy(&u, &d, 8);
    lbk_wr64(p, u);
}

#endif
