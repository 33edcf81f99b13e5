/* lbk view: the level with its baked lighting, as a runtime applies it.
 *
 * Data: data.js sets window.LBK_DATA = {lbk: base64 container, glb: base64 glTF (lbk export --gltf
 * of the scene: world-space nodes in OBJS order, TEXCOORD_1 = normalised page uv), name}. The
 * container is read by lbk_reader.js (the page's own reader of spec/container.md).
 *
 * Lightmapped surfaces: the two LMAP planes are uploaded as stored (R32UI R11G11B10F words, RGBA8UI
 * bytes); a block-encoded page (BC6H, BC5 + BC4; spec §9.2) is decoded by lbk_reader.js to liblbk's
 * float texel form (Ez RGB, r, X, Y, Z; two RGBA32F textures), as lbk render's loader does; ASTC
 * pages are not decoded (the page says so; their objects are lit from the GLG instead). The
 * fragment shader does what tools/render/shade.c does per pixel: bilinear over the
 * four texels around (X − ½, Y − ½) (clamped to the page), each decoded by spec §5.6 to the linear
 * form and blended there, evaluated along the shading normal (+Z of the tangent frame; with a
 * normal map, the mapped normal in that frame: viewer/README.md "Normal maps"), × the section's
 * scale. Radiance = albedo · E / π. LLG objects: V · E_sh(bent normal) of
 * the grid's trilinear SH at each vertex (spec §11), interpolated. Other objects: the GLG at each
 * vertex. Display: radiance × 2^stops, clamped, sRGB-encoded.
 *
 * URL hash (for tests and links): cam=fx,fy,fz,ax,ay,az,ux,uy,uz,yfov_degrees, stops=S, mode=M,
 * size=WxH, sets=NAME:W,..., doors=NAME:W,..., show=glg,llg,octp,sphere, sphere=fx,fy,fz (fractions of the
 * level's half extents from its centre). window.lbkViewReady becomes true when the first frame is drawn. */
(function () {
  'use strict';
  const $ = (id) => document.getElementById(id);
  const status = (s) => { $('status').textContent = s; };
  const fail = (e) => {
    $('error').textContent = String(e && e.message || e); status('error'); console.error(e);
    document.title = 'lbk view: failed, ' + window.lbkErrors.length + ' errors';
  };

  function b64(s) {
    const bin = atob(s), u8 = new Uint8Array(bin.length);
    for (let i = 0; i < bin.length; i++) u8[i] = bin.charCodeAt(i);
    return u8;
  }
  function params() {
    const out = {};
    for (const kv of location.hash.replace(/^#/, '').split('&')) {
      const i = kv.indexOf('=');
      if (i > 0) out[decodeURIComponent(kv.slice(0, i))] = decodeURIComponent(kv.slice(i + 1));
    }
    return out;
  }

  /* world space throughout: the export's nodes have identity transforms */
  const VERT = `
    attribute vec2 uv2;
    attribute vec4 lbkTangent;
    varying vec2 vCoord;
    varying vec2 vUv;
    varying vec3 vNormal;
    varying vec3 vPos;
    varying vec4 vTangent;
    varying vec3 vColor;
    attribute vec3 lbkColor;
    uniform vec2 pageSize;
    void main() {
      vCoord = uv2 * pageSize;
      vUv = uv;
      vNormal = normalize(normal);
      vPos = position;
      vTangent = lbkTangent;
      vColor = lbkColor;
      gl_Position = projectionMatrix * modelViewMatrix * vec4(position, 1.0);
    }`;
  /* R11G11B10F decode (spec §5.1) and the AHD linear form (§5.6) */
  const FRAG = `
    precision highp float;
    precision highp usampler2D;
    precision highp sampler2D;
    uniform usampler2D plane0;
    uniform usampler2D plane1;
    uniform usampler2D footprint;
    uniform usampler2D errmap;
    uniform sampler2D block0;
    uniform sampler2D block1;
    uniform int blockPage;
    uniform int hasErr;
    uniform vec2 pageSize;
    uniform float scale;
    uniform vec3 albedo;
    uniform vec3 emission;
    uniform float exposure;
    uniform int mode;
    uniform int lightmapped;
    uniform sampler2D normalMap;
    uniform int hasNormalMap;
    uniform float normalScale;
    varying vec2 vCoord;
    varying vec2 vUv;
    varying vec3 vNormal;
    varying vec3 vPos;
    varying vec4 vTangent;
    varying vec3 vColor;
    float small(uint code, uint mbits) {
      uint e = code >> mbits, m = code & ((1u << mbits) - 1u);
      if (e == 0u) return float(m) * exp2(-14.0 - float(mbits));
      if (e == 31u) return 65024.0;
      return (1.0 + float(m) / float(1u << mbits)) * exp2(float(e) - 15.0);
    }
    /* e0 + g·n per channel: the linear form along n, the shading normal in the texel's tangent
     * frame (+Z without a normal map: then d.z, the bits of the form along +Z exactly) */
    float along(vec3 d, vec3 n) { return hasNormalMap == 1 ? dot(d, n) : d.z; }
    vec3 blockTexelE(ivec2 t, vec3 n) { /* lbk_ahd_texel_f_to_linear, evaluated along n */
      vec4 a = texelFetch(block0, t, 0), b = texelFetch(block1, t, 0);
      vec3 d = vec3(2.0 * b.x - 1.0, 2.0 * b.y - 1.0, b.z);
      float len = length(d);
      d = len >= 0.5 ? d / len : vec3(0.0, 0.0, 1.0);
      float r = clamp(a.a, 0.0, 1.0);
      vec3 ez = clamp(a.rgb, 0.0, 65504.0);
      float k = 0.25 + 0.5 * d.z;
      vec3 amb = r * ez, inten = (1.0 - r) * ez / k;
      return amb + 0.25 * inten + 0.5 * inten * along(d, n);
    }
    vec3 texelE(ivec2 t, vec3 n) {
      if (blockPage == 1) return blockTexelE(t, n);
      uint w = texelFetch(plane0, t, 0).r;
      uvec4 b = texelFetch(plane1, t, 0);
      vec3 ez = vec3(small(w & 2047u, 6u), small((w >> 11) & 2047u, 6u), small(w >> 22, 5u));
      vec3 d = vec3(2.0 * float(b.g) / 255.0 - 1.0, 2.0 * float(b.b) / 255.0 - 1.0, float(b.a) / 255.0);
      float len = length(d);
      d = len < 0.5 ? vec3(0.0, 0.0, 1.0) : d / len;
      float r = float(b.r) / 255.0;
      float k = 0.25 + 0.5 * d.z;
      vec3 amb = r * ez, inten = (1.0 - r) * ez / k;
      return amb + 0.25 * inten + 0.5 * inten * along(d, n);
    }
    /* The normal map's world normal (glTF: t = (2·rgb − 1) with x, y × scale, in the frame T, B =
     * w (N × T), N; bilinear, repeat, as lbk render), as tools/render/shade.c shading_normal. */
    vec3 mappedNormal(vec3 N) {
      vec3 T = vTangent.xyz - N * dot(N, vTangent.xyz);
      if (dot(T, T) <= 0.0) return N;
      T = normalize(T);
      vec3 B = cross(N, T) * (vTangent.w < 0.0 ? -1.0 : 1.0);
      vec3 t = texture2D(normalMap, vUv).rgb * 2.0 - 1.0;
      vec3 n = t.x * normalScale * T + t.y * normalScale * B + t.z * N;
      return dot(n, n) > 1e-12 ? normalize(n) : N;
    }
    /* n in the texel's tangent frame (spec §5.6, lbk_ahd_triangle_dpdx + lbk_ahd_tangent_frame):
     * T = dP/dX of the triangle made orthogonal to N, B = N × T; dP/dX from the screen-space
     * derivatives of the (per triangle affine) position and lightmap coordinate. */
    vec3 texelFrame(vec3 N, vec3 n) {
      vec3 dp1 = dFdx(vPos), dp2 = dFdy(vPos);
      vec2 dc1 = dFdx(vCoord), dc2 = dFdy(vCoord);
      float det = dc1.x * dc2.y - dc2.x * dc1.y;
      vec3 dpdx = det != 0.0 ? (dp1 * dc2.y - dp2 * dc1.y) / det : vec3(0.0);
      vec3 T = dpdx - N * dot(N, dpdx);
      if (!(length(T) > 1e-6 * length(dpdx))) { /* basis_t of libformat/src/ahd_frame.c */
        float sg = N.z >= 0.0 ? 1.0 : -1.0, a = -1.0 / (sg + N.z);
        T = vec3(1.0 + sg * N.x * N.x * a, sg * N.x * N.y * a, -sg * N.x);
      }
      T = normalize(T);
      vec3 B = normalize(cross(N, T));
      return vec3(dot(n, T), dot(n, B), dot(n, N));
    }
    vec3 lightmapE() {
      vec3 N = normalize(vNormal), nt = vec3(0.0, 0.0, 1.0);
      if (hasNormalMap == 1) nt = texelFrame(N, mappedNormal(N));
      vec2 f = vCoord - 0.5;
      vec2 i0 = floor(f), a = f - i0;
      vec3 e = vec3(0.0);
      for (int k = 0; k < 4; k++) {
        vec2 o = vec2(float(k & 1), float((k >> 1) & 1));
        float w = (o.x > 0.5 ? a.x : 1.0 - a.x) * (o.y > 0.5 ? a.y : 1.0 - a.y);
        ivec2 t = ivec2(clamp(i0 + o, vec2(0.0), pageSize - 1.0));
        e += w * texelE(t, nt);
      }
      return max(e * scale, 0.0);
    }
    /* the error map's colour scale (tools/convert/export.c error_colour): log10 of the relative
     * error from 0.1 % to 100 %; display values (no sRGB encoding) */
    vec3 errColour(float rel) {
      vec3 s0 = vec3(0.05, 0.15, 0.6), s1 = vec3(0.0, 0.55, 0.9), s2 = vec3(0.1, 0.8, 0.3), s3 = vec3(0.95, 0.85, 0.1), s4 = vec3(0.85, 0.1, 0.1);
      float t = clamp((log(max(rel, 1e-12)) / log(10.0) + 3.0) / 3.0, 0.0, 1.0) * 4.0;
      if (t < 1.0) return mix(s0, s1, t);
      if (t < 2.0) return mix(s1, s2, t - 1.0);
      if (t < 3.0) return mix(s2, s3, t - 2.0);
      return mix(s3, s4, t - 3.0);
    }
    float srgb(float x) { x = clamp(x, 0.0, 1.0); return x <= 0.0031308 ? 12.92 * x : 1.055 * pow(x, 1.0 / 2.4) - 0.055; }
    void main() {
      if (!gl_FrontFacing && lightmapped == 1) { gl_FragColor = vec4(0.0, 0.0, 0.0, 1.0); return; }
      if (mode == 5) { /* per-texel error (TERR, spec §18): texels of lightmapped surfaces only */
        vec3 g = vec3(0.25);
        if (lightmapped == 1 && hasErr == 1) {
          uint code = texelFetch(errmap, ivec2(clamp(floor(vCoord), vec2(0.0), pageSize - 1.0)), 0).r;
          if (code != 0u) g = errColour(exp2((float(code) - 161.0) / 16.0));
        } else if (lightmapped == 0) g = albedo * 0.2;
        gl_FragColor = vec4(g, 1.0);
        return;
      }
      vec3 E = lightmapped == 1 ? lightmapE() : vColor;
      vec3 c;
      if (mode == 1) c = E * exposure;
      else if (mode == 3) c = albedo;
      else if (mode == 2) {
        vec2 g = abs(fract(vCoord) - 0.5);
        float line = lightmapped == 1 && max(g.x, g.y) > 0.45 ? 1.0 : 0.0;
        c = mix(albedo * 0.6, vec3(1.0, 0.3, 0.1), line);
      } else c = (albedo * E / 3.14159265358979 + emission) * exposure;
      if (mode == 4) {
        float m = lightmapped == 1 ? float(texelFetch(footprint, ivec2(clamp(floor(vCoord), vec2(0.0), pageSize - 1.0)), 0).r) : 0.0;
        c = mix(c, vec3(0.1, 0.9, 1.0), 0.6 * m);
      }
      gl_FragColor = vec4(srgb(c.r), srgb(c.g), srgb(c.b), 1.0);
    }`;

  /* ---- probes on the CPU: GLG (tetra barycentrics with visibility, §10), LLG (§11) ----------- */
  const Y0 = 0.282094791773878, Y1 = 0.488602511902920, Y2a = 1.092548430592079, Y20 = 0.315391565252520, Y22 = 0.546274215296040;
  const A0 = Math.PI, A1 = 2 * Math.PI / 3, A2 = Math.PI / 4;
  function shIrradiance(sh, o, n) {
    const [x, y, z] = n;
    const b = [A0 * Y0, A1 * Y1 * y, A1 * Y1 * z, A1 * Y1 * x, A2 * Y2a * x * y, A2 * Y2a * y * z,
               A2 * Y20 * (3 * z * z - 1), A2 * Y2a * x * z, A2 * Y22 * (x * x - y * y)];
    const e = [0, 0, 0];
    for (let c = 0; c < 3; c++) for (let k = 0; k < 9; k++) e[c] += sh[o + 27 * 0 + c * 9 + k] * b[k];
    return e.map((v) => Math.max(0, v));
  }
  function glgSample(glg, p) {
    const P = glg.positions, T = glg.tetra_count;
    let best = -Infinity, bestT = 0, bestB = null;
    for (let t = 0; t < T; t++) {
      const v = [0, 1, 2, 3].map((i) => glg.tetras[4 * t + i]);
      const q = v.map((i) => [P[3 * i], P[3 * i + 1], P[3 * i + 2]]);
      const det = (a, b, c, d) => {
        const u = [b[0] - a[0], b[1] - a[1], b[2] - a[2]], w = [c[0] - a[0], c[1] - a[1], c[2] - a[2]], s = [d[0] - a[0], d[1] - a[1], d[2] - a[2]];
        return u[0] * (w[1] * s[2] - w[2] * s[1]) - u[1] * (w[0] * s[2] - w[2] * s[0]) + u[2] * (w[0] * s[1] - w[1] * s[0]);
      };
      const vol = det(q[0], q[1], q[2], q[3]);
      if (!(vol > 0)) continue;
      const b = [0, 1, 2, 3].map((i) => { const r = q.slice(); r[i] = p; return det(r[0], r[1], r[2], r[3]) / vol; });
      const m = Math.min(...b);
      if (m > best) { best = m; bestT = t; bestB = b; }
      if (m >= -1e-6) break;
    }
    const out = new Float32Array(27);
    if (!bestB) return out;
    let b = bestB.map((x) => Math.max(0, x)), s = b.reduce((x, y) => x + y, 0);
    b = b.map((x) => x / (s || 1));
    let w = b.map((x, i) => x * glg.visibility[4 * bestT + i] / 255), ws = w.reduce((x, y) => x + y, 0);
    w = ws > 0 ? w.map((x) => x / ws) : b;
    for (let i = 0; i < 4; i++) {
      const pr = glg.tetras[4 * bestT + i];
      for (let k = 0; k < 27; k++) out[k] += w[i] * glg.sh[27 * pr + k];
    }
    return out;
  }
  function llgSample(g, p) {
    const i0 = [], f = [];
    for (let a = 0; a < 3; a++) {
      const ax = g.axes[a];
      let l = ((p[0] - g.centre[0]) * ax[0] + (p[1] - g.centre[1]) * ax[1] + (p[2] - g.centre[2]) * ax[2]) / g.half_extents[a];
      l = Math.min(1, Math.max(-1, l));
      const gc = (l + 1) / 2 * (g.n[a] - 1);
      const i = Math.min(Math.floor(gc), g.n[a] - 2);
      i0.push(i); f.push(gc - i);
    }
    const out = new Float32Array(27);
    for (let c = 0; c < 8; c++) {
      const o = [c & 1, (c >> 1) & 1, (c >> 2) & 1];
      const w = (o[0] ? f[0] : 1 - f[0]) * (o[1] ? f[1] : 1 - f[1]) * (o[2] ? f[2] : 1 - f[2]);
      const idx = (i0[0] + o[0]) + g.n[0] * ((i0[1] + o[1]) + g.n[1] * (i0[2] + o[2]));
      for (let k = 0; k < 27; k++) out[k] += w * g.sh[27 * idx + k];
    }
    return out;
  }

  /* lbk_octp_irradiance: the octahedral map of §14, bilinear on the 6 × 6 stored grid (border included) */
  function octIrradiance(p, d) {
    const sum = Math.abs(d[0]) + Math.abs(d[1]) + Math.abs(d[2]);
    let u = 0, v = 0;
    if (sum > 0) {
      const x = d[0] / sum, y = d[1] / sum, sg = (a) => (a >= 0 ? 1 : -1);
      if (d[2] >= 0) { u = x; v = y; } else { u = (1 - Math.abs(y)) * sg(x); v = (1 - Math.abs(x)) * sg(y); }
    }
    const st = [u, v].map((a) => Math.min(5, Math.max(0, (a + 1) * 0.5 * 4 + 0.5)));
    const i0 = st.map((a) => Math.min(4, Math.floor(a))), f = st.map((a, k) => a - i0[k]);
    const rgb = [0, 0, 0];
    for (let dy = 0; dy < 2; dy++) for (let dx = 0; dx < 2; dx++) {
      const w = (dx ? f[0] : 1 - f[0]) * (dy ? f[1] : 1 - f[1]), o = 3 * ((i0[1] + dy) * 6 + i0[0] + dx);
      for (let k = 0; k < 3; k++) rgb[k] += w * p.irradiance_full[o + k];
    }
    return rgb;
  }
  function unpackProbes(u8, scale) {
    const n = u8.length / 28, out = new Float32Array(27 * n);
    for (let i = 0; i < n; i++) out.set(LbkReader.sh9Unpack(u8, 28 * i, scale), 27 * i);
    return out;
  }
  /* the stored base of every DLS space, as lbk_dls_apply reads it */
  async function dlsBase(lbk, lmap, glg, llg) {
    const base = { z: null, rgba: null, glg: null, llg: null };
    if (lmap) {
      base.z = new Uint32Array(lmap.texel_count); base.rgba = new Uint8Array(4 * lmap.texel_count);
      for (const pg of lmap.pages) {
        if (pg.format0 || pg.format1) continue;
        const v = new DataView(pg.plane0.buffer, pg.plane0.byteOffset, pg.plane0.length);
        for (let t = 0; t < pg.width * pg.height; t++) base.z[pg.first_texel + t] = v.getUint32(4 * t, true);
        base.rgba.set(pg.plane1, 4 * pg.first_texel);
      }
    }
    const a16 = (x) => Math.ceil(x / 16) * 16;
    if (glg) { const p = await lbk.payload('GLG '), o = a16(32 + 12 * glg.probe_count); base.glg = p.slice(o, o + 28 * glg.probe_count); }
    if (llg) {
      const p = await lbk.payload('LLG '), o = a16(32 + 96 * llg.grids.length), n = llg.grids.reduce((a, g) => a + g.sh.length / 27, 0);
      base.llg = p.slice(o, o + 28 * n);
    }
    return base;
  }
  /* One slider per light set (kind 0; default 1, on, as lbk render) and per door (ω, default 0,
   * closed); hash parameters sets=NAME:W,... and doors=NAME:W,... set them. */
  function dlsControls(dls, doors, P) {
    const box = $('sets'), sel = $('footprint-set');
    const given = (s) => { const m = {}; for (const kv of (s || '').split(',')) { const i = kv.lastIndexOf(':'); if (i > 0) m[kv.slice(0, i)] = Number(kv.slice(i + 1)); } return m; };
    const gs = given(P.sets), gd = given(P.doors);
    const sliders = [], doorSliders = [];
    const add = (label, value) => {
      const l = document.createElement('label'), r = document.createElement('input'), v = document.createElement('span');
      r.type = 'range'; r.min = '0'; r.max = '1'; r.step = '0.01'; r.value = String(value);
      const show = () => { v.textContent = ' ' + Number(r.value).toFixed(2); };
      r.addEventListener('input', show); show();
      l.append(label + ' ', r, v); box.appendChild(l);
      return r;
    };
    if (!dls) { box.textContent = 'no DLS section: the lighting is static'; }
    else {
      dls.sets.forEach((s, i) => {
        if (s.kind === 0) sliders.push([i, add('set ' + s.name, s.name in gs ? gs[s.name] : 1)]);
        if (s.kind === 0 || s.kind === 1) {
          const o = document.createElement('option'); o.value = String(i); o.textContent = s.name; sel.appendChild(o);
        }
      });
      (doors || []).forEach((d) => doorSliders.push(add('door ' + d.name, d.name in gd ? gd[d.name] : 0)));
    }
    return {
      setWeights: () => { const w = new Array(dls ? dls.sets.length : 0).fill(0); for (const [i, r] of sliders) w[i] = Number(r.value); return w; },
      doorWeights: () => doorSliders.map((r) => Number(r.value)),
    };
  }

  async function main() {
    const P = params();
    const data = window.LBK_DATA;
    if (!data) throw new Error('data.js did not load (open the folder that lbk view wrote)');
    const deps = { decompress: (u8) => fzstd.decompress(u8), xxh3: (u8) => hashwasm.xxhash3(u8) };
    const lbk = await LbkReader.open(b64(data.lbk), deps);
    const [meta, rept, objs, lmap, glg, llg, dls, doors, octp, emap] = await Promise.all([lbk.meta(), lbk.report(), lbk.objects(), lbk.lightmap(),
      lbk.glg(), lbk.llg(), lbk.dls(), lbk.doors(), lbk.octp(), lbk.errorMap()]);
    const base = await dlsBase(lbk, lmap, glg, llg);
    panel(data, lbk, meta, rept, objs, lmap, glg);

    const wrap = $('canvas-wrap');
    let w = wrap.clientWidth, h = wrap.clientHeight;
    if (P.size) { /* a fixed-size canvas without the panel: for screenshots (tests) */
      [w, h] = P.size.split('x').map(Number);
      document.body.classList.add('shot');
    }
    const renderer = new THREE.WebGLRenderer({ antialias: false, preserveDrawingBuffer: true });
    if (!renderer.capabilities.isWebGL2) throw new Error('this page needs WebGL 2');
    renderer.setPixelRatio(1);
    renderer.setSize(w, h);
    renderer.outputEncoding = THREE.LinearEncoding; /* the shader writes sRGB itself */
    wrap.appendChild(renderer.domElement);
    const scene = new THREE.Scene();
    scene.background = new THREE.Color(0, 0, 0);

    /* pages: 1.0 planes as stored; block pages (BC6H, BC5 + BC4) decoded to the float texel form;
     * ASTC pages not drawn (no ASTC decoder in the page): null, their objects lit from the GLG */
    const tex = (data, w, h, format, type, internal) => {
      const t = new THREE.DataTexture(data, w, h, format, type);
      t.internalFormat = internal;
      t.magFilter = t.minFilter = THREE.NearestFilter; t.generateMipmaps = false; t.flipY = false; t.needsUpdate = true;
      return t;
    };
    const astcPages = [];
    const pages = (lmap ? lmap.pages : []).map((pg, i) => {
      if (pg.format0 === 2 || pg.format1 === 2) { astcPages.push(i); return null; }
      const n = pg.width * pg.height, block = !!(pg.format0 || pg.format1);
      const t0 = tex(new Uint32Array(block ? 1 : n), block ? 1 : pg.width, block ? 1 : pg.height, THREE.RedIntegerFormat, THREE.UnsignedIntType, 'R32UI');
      const t1 = tex(block ? new Uint8Array(4) : new Uint8Array(pg.plane1), block ? 1 : pg.width, block ? 1 : pg.height, THREE.RGBAIntegerFormat, THREE.UnsignedByteType, 'RGBA8UI');
      /* the light-set footprint: 1 where the chosen set has an entry */
      const t2 = tex(new Uint8Array(n), pg.width, pg.height, THREE.RedIntegerFormat, THREE.UnsignedByteType, 'R8UI');
      let b0 = null, b1 = null;
      if (block) {
        const tf = LbkReader.pageTexelsF(pg), a = new Float32Array(4 * n), b = new Float32Array(4 * n);
        for (let t = 0; t < n; t++) { a.set(tf.subarray(7 * t, 7 * t + 4), 4 * t); b.set(tf.subarray(7 * t + 4, 7 * t + 7), 4 * t); }
        b0 = tex(a, pg.width, pg.height, THREE.RGBAFormat, THREE.FloatType, 'RGBA32F');
        b1 = tex(b, pg.width, pg.height, THREE.RGBAFormat, THREE.FloatType, 'RGBA32F');
      }
      /* the per-texel error map's codes (TERR, §18), R8UI; none without the section */
      const te = emap ? tex(new Uint8Array(emap.codes.subarray(pg.first_texel, pg.first_texel + n)), pg.width, pg.height,
                            THREE.RedIntegerFormat, THREE.UnsignedByteType, 'R8UI') : null;
      return { t0, t1, t2, te, b0, b1, block, first: pg.first_texel, n, size: new THREE.Vector2(pg.width, pg.height) };
    });
    if (astcPages.length)
      $('note').textContent = 'ASTC pages cannot be shown: this page has no ASTC decoder (page' + (astcPages.length > 1 ? 's ' : ' ') +
        astcPages.join(', ') + '; their objects are lit from the GLG instead). Open the pack with lbk view, which decodes ASTC pages for this page.';

    /* The glTF's textures (lbk export's lightmap previews) are never drawn here, so none is loaded:
     * an image decodes off the main thread, which headless Chromium's virtual time does not wait
     * for, and a test's page could be read before it was ready. */
    const loader = new THREE.GLTFLoader();
    loader.register(() => ({ name: 'lbk_no_textures', loadTexture: () => Promise.resolve(null) }));
    const gltf = await new Promise((res, rej) => loader.parse(b64(data.glb).buffer, '', res, rej));
    const uniformsCommon = { exposure: { value: 1 }, mode: { value: 0 } };
    const box = new THREE.Box3();
    const dummy = pages.find((p) => p) || null;
    const dummyTex = () => { const t = new THREE.DataTexture(new Uint32Array(1), 1, 1, THREE.RedIntegerFormat, THREE.UnsignedIntType); t.internalFormat = 'R32UI'; t.needsUpdate = true; return t; };
    const dummyTex1 = () => { const t = new THREE.DataTexture(new Uint8Array(4), 1, 1, THREE.RGBAIntegerFormat, THREE.UnsignedByteType); t.internalFormat = 'RGBA8UI'; t.needsUpdate = true; return t; };
    const dummyTex2 = () => { const t = new THREE.DataTexture(new Uint8Array(1), 1, 1, THREE.RedIntegerFormat, THREE.UnsignedByteType); t.internalFormat = 'R8UI'; t.needsUpdate = true; return t; };
    const dummyF = () => tex(new Float32Array(4), 1, 1, THREE.RGBAFormat, THREE.FloatType, 'RGBA32F');
    const probeLit = []; /* meshes lit per vertex from the probes: recomputed when the sets change */
    const meshes = [];
    gltf.scene.traverse((m) => { if (m.isMesh) meshes.push(m); });
    /* normal maps: lbk view's export puts each one's texels in its material's extras (RGB bytes,
     * row 0 the image's top = v 0), read here synchronously (no image decode); sampled bilinearly
     * with repeat (no mipmaps), as lbk render does. Drawn on lightmapped surfaces (probe-lit ones are lit per
     * vertex and keep their vertex normals). */
    const normalMaps = new Map();
    for (const m of meshes) {
      const nm = m.material.userData && m.material.userData.lbk && m.material.userData.lbk.normal_map;
      if (!nm || normalMaps.has(nm.texels)) continue;
      const acc = await gltf.parser.getDependency('accessor', nm.texels);
      const n = nm.width * nm.height, rgb = acc.array, rgba = new Uint8Array(4 * n);
      if (rgb.length !== 3 * n) throw new Error('normal map texels: ' + rgb.length + ' bytes for ' + nm.width + 'x' + nm.height);
      for (let i = 0; i < n; i++) { rgba[4 * i] = rgb[3 * i]; rgba[4 * i + 1] = rgb[3 * i + 1]; rgba[4 * i + 2] = rgb[3 * i + 2]; rgba[4 * i + 3] = 255; }
      const t = new THREE.DataTexture(rgba, nm.width, nm.height, THREE.RGBAFormat, THREE.UnsignedByteType);
      t.magFilter = t.minFilter = THREE.LinearFilter; t.wrapS = t.wrapT = THREE.RepeatWrapping;
      t.generateMipmaps = false; t.flipY = false; t.needsUpdate = true;
      normalMaps.set(nm.texels, t);
    }
    const noNormalMap = new THREE.DataTexture(new Uint8Array([128, 128, 255, 255]), 1, 1, THREE.RGBAFormat, THREE.UnsignedByteType);
    noNormalMap.needsUpdate = true;
    for (const m of meshes) {
      let node = m, info = null;
      while (node && !(info = node.userData && node.userData.lbk)) node = node.parent;
      const prim = m.geometry.userData && m.geometry.userData.lbk;
      const matx = m.material.userData && m.material.userData.lbk;
      const albedo = matx && matx.albedo ? new THREE.Vector3().fromArray(matx.albedo) : new THREE.Vector3(m.material.color.r, m.material.color.g, m.material.color.b);
      const emission = new THREE.Vector3().fromArray(matx && matx.emission ? matx.emission : [0, 0, 0]);
      const g = m.geometry;
      const n = g.attributes.position.count, colors = new Float32Array(3 * n);
      const rep = info ? info.representation : 'none';
      const pageIdx = prim && prim.lightmap ? prim.lightmap.page : -1;
      const page = pageIdx >= 0 ? pages[pageIdx] : null;
      g.setAttribute('lbkColor', new THREE.BufferAttribute(colors, 3));
      if (rep !== 'lightmap' || !page) probeLit.push({ g, grid: rep === 'llg' ? info.llg_grid : -1 });
      if (!g.attributes.uv2) g.setAttribute('uv2', new THREE.BufferAttribute(new Float32Array(2 * n), 2));
      if (!g.attributes.uv) g.setAttribute('uv', new THREE.BufferAttribute(new Float32Array(2 * n), 2));
      const nm = matx && matx.normal_map && g.attributes.tangent && page ? matx.normal_map : null;
      g.setAttribute('lbkTangent', nm ? g.attributes.tangent : new THREE.BufferAttribute(new Float32Array(4 * n), 4));
      const src = page || dummy;
      const mat = new THREE.ShaderMaterial({
        vertexShader: VERT, fragmentShader: FRAG, side: THREE.DoubleSide,
        uniforms: { plane0: { value: page ? page.t0 : dummyTex() }, plane1: { value: page ? page.t1 : dummyTex1() },
                    footprint: { value: page ? page.t2 : dummyTex2() }, errmap: { value: page && page.te ? page.te : dummyTex2() },
                    block0: { value: page && page.block ? page.b0 : dummyF() }, block1: { value: page && page.block ? page.b1 : dummyF() },
                    blockPage: { value: page && page.block ? 1 : 0 }, hasErr: { value: page && page.te ? 1 : 0 },
                    pageSize: { value: src ? src.size.clone() : new THREE.Vector2(1, 1) }, scale: { value: lmap ? lmap.scale : 1 },
                    albedo: { value: albedo }, emission: { value: emission }, lightmapped: { value: page ? 1 : 0 },
                    normalMap: { value: nm ? normalMaps.get(nm.texels) : noNormalMap }, hasNormalMap: { value: nm ? 1 : 0 },
                    normalScale: { value: nm ? nm.scale : 1 },
                    exposure: uniformsCommon.exposure, mode: uniformsCommon.mode } });
      m.material = mat;
      box.expandByObject(m);
    }
    scene.add(gltf.scene);

    /* E per vertex of the probe-lit meshes from the current probes (glgNow, llgNow) */
    let glgNow = glg, llgNow = llg;
    const relight = () => {
      for (const { g, grid: gi } of probeLit) {
        const pos = g.attributes.position, nor = g.attributes.normal, col = g.attributes.lbkColor;
        const grid = gi >= 0 && llgNow ? llgNow.grids[gi] : null;
        const vis = g.attributes._lbk_llg_visibility, bent = g.attributes._lbk_llg_bent_normal;
        for (let i = 0; i < pos.count; i++) {
          const p = [pos.getX(i), pos.getY(i), pos.getZ(i)];
          let e = [0, 0, 0];
          if (grid && vis && bent) {
            const b = new THREE.Vector3(bent.getX(i), bent.getY(i), bent.getZ(i)).normalize();
            e = shIrradiance(llgSample(grid, p), 0, [b.x, b.y, b.z]).map((v) => v * vis.getX(i));
          } else if (glgNow && nor) {
            e = shIrradiance(glgSample(glgNow, p), 0, [nor.getX(i), nor.getY(i), nor.getZ(i)]);
          }
          col.array.set(e, 3 * i);
        }
        col.needsUpdate = true;
      }
    };
    /* light sets and doors: §12.8 in the page (lbk_reader.js dlsApply), then the planes re-uploaded */
    const controls0 = dlsControls(dls, doors, P);
    let lastOut = base;
    const applySets = () => {
      let out = base;
      if (dls) out = LbkReader.dlsApply(dls, doors, base, controls0.setWeights(), controls0.doorWeights());
      pages.forEach((pg) => {
        if (!pg || pg.block) return; /* block pages: the stored base (DLS entries are applied to 1.0 pages only) */
        pg.t0.image.data.set(out.z.subarray(pg.first, pg.first + pg.n)); pg.t0.needsUpdate = true;
        pg.t1.image.data.set(out.rgba.subarray(4 * pg.first, 4 * (pg.first + pg.n))); pg.t1.needsUpdate = true;
      });
      if (glg && out.glg) glgNow = Object.assign({}, glg, { sh: unpackProbes(out.glg, glg.scale) });
      if (llg && out.llg) {
        const all = unpackProbes(out.llg, llg.scale);
        let o = 0;
        llgNow = Object.assign({}, llg, { grids: llg.grids.map((gr) => { const n = gr.sh.length; const sh = all.subarray(o, o + n); o += n; return Object.assign({}, gr, { sh }); }) });
      }
      relight();
      lastOut = out;
    };
    const footprint = () => {
      const sel = Number($('footprint-set').value);
      pages.forEach((pg) => { if (pg) pg.t2.image.data.fill(0); });
      if (dls && sel >= 0)
        for (const c of dls.clusters) {
          if (c.space !== 0 || c.sets.indexOf(sel) < 0) continue;
          dls.forEachTarget(c, (t, list) => {
            if (!list.some(([s]) => s === sel)) return;
            const pg = pages.find((q) => q && t >= q.first && t < q.first + q.n);
            if (pg) pg.t2.image.data[t - pg.first] = 1;
          });
        }
      pages.forEach((pg) => { if (pg) pg.t2.needsUpdate = true; });
    };
    applySets();
    footprint();

    /* probe glyphs: a small sphere per probe, each vertex coloured by the probe's irradiance for
     * its normal (GLG, LLG lattice: SH9 of §5.5; OCTP: the octahedral map, bilinear with its border) */
    const diag = box.getSize(new THREE.Vector3()).length();
    const glyphMaterial = (mode) => new THREE.ShaderMaterial({ vertexShader: VERT, fragmentShader: FRAG,
      uniforms: { plane0: { value: dummyTex() }, plane1: { value: dummyTex1() }, footprint: { value: dummyTex2() }, errmap: { value: dummyTex2() },
                  block0: { value: dummyF() }, block1: { value: dummyF() }, blockPage: { value: 0 }, hasErr: { value: 0 },
                  pageSize: { value: new THREE.Vector2(1, 1) }, scale: { value: 1 }, albedo: { value: new THREE.Vector3(1, 1, 1) },
                  emission: { value: new THREE.Vector3() }, lightmapped: { value: 0 }, exposure: uniformsCommon.exposure, mode,
                  normalMap: { value: noNormalMap }, hasNormalMap: { value: 0 }, normalScale: { value: 1 } } });
    const glyphMode = { value: 1 }; /* glyphs show irradiance ×(exposure); in radiance mode × 1/π */
    const sphere = (r) => { const g = new THREE.SphereGeometry(r, 12, 8); g.setAttribute('uv2', new THREE.BufferAttribute(new Float32Array(2 * g.attributes.position.count), 2)); return g; };
    const glyphGroup = (positions, colourOf) => {
      const grp = new THREE.Group(), sg = sphere(diag * 0.006);
      positions.forEach((pos, i) => {
        const gi = sg.clone(), nor = gi.attributes.normal, c = new Float32Array(3 * nor.count);
        for (let v = 0; v < nor.count; v++) c.set(colourOf(i, [nor.getX(v), nor.getY(v), nor.getZ(v)]), 3 * v);
        gi.setAttribute('lbkColor', new THREE.BufferAttribute(c, 3));
        const m = new THREE.Mesh(gi, glyphMaterial(glyphMode));
        m.position.set(pos[0], pos[1], pos[2]);
        grp.add(m);
      });
      grp.visible = false;
      scene.add(grp);
      return grp;
    };
    const groups = {};
    const buildGlyphs = () => {
      for (const k of Object.keys(groups)) scene.remove(groups[k]);
      if (glgNow) {
        const pos = []; for (let i = 0; i < glgNow.probe_count; i++) pos.push([glgNow.positions[3 * i], glgNow.positions[3 * i + 1], glgNow.positions[3 * i + 2]]);
        groups.glg = glyphGroup(pos, (i, n) => shIrradiance(glgNow.sh, 27 * i, n));
      }
      if (llgNow) {
        const pos = [], at = [];
        llgNow.grids.forEach((g) => {
          for (let k = 0; k < g.n[2]; k++) for (let j = 0; j < g.n[1]; j++) for (let i = 0; i < g.n[0]; i++) {
            const t = [i / (g.n[0] - 1) * 2 - 1, j / (g.n[1] - 1) * 2 - 1, k / (g.n[2] - 1) * 2 - 1], p = g.centre.slice();
            for (let a = 0; a < 3; a++) for (let c = 0; c < 3; c++) p[c] += g.axes[a][c] * g.half_extents[a] * t[a];
            pos.push(p); at.push([g, i + g.n[0] * (j + g.n[1] * k)]);
          }
        });
        groups.llg = glyphGroup(pos, (q, n) => shIrradiance(at[q][0].sh, 27 * at[q][1], n));
      }
      /* a volume's probes inside geometry (state 1) hold no light (§14.2): no glyph */
      const lit = octp ? octp.probes.filter((p) => p.state !== 1) : [];
      if (octp) groups.octp = glyphGroup(lit.map((p) => p.position), (i, n) => octIrradiance(lit[i], n));
      for (const [k, id] of [['glg', 'probes'], ['llg', 'probes-llg'], ['octp', 'probes-octp']]) if (groups[k]) groups[k].visible = $(id).checked;
    };
    buildGlyphs();

    /* the test sphere: white, lit from the GLG per vertex (as lbk render --probe-spheres) */
    const ctr0 = box.getCenter(new THREE.Vector3()), size0 = box.getSize(new THREE.Vector3());
    const sg = new THREE.SphereGeometry(diag * 0.05, 32, 16);
    sg.setAttribute('uv2', new THREE.BufferAttribute(new Float32Array(2 * sg.attributes.position.count), 2));
    sg.setAttribute('lbkColor', new THREE.BufferAttribute(new Float32Array(3 * sg.attributes.position.count), 3));
    const testSphere = new THREE.Mesh(sg, glyphMaterial(uniformsCommon.mode));
    testSphere.visible = false;
    scene.add(testSphere);
    const placeSphere = () => {
      const f = ['sx', 'sy', 'sz'].map((id) => Number($(id).value));
      testSphere.position.set(ctr0.x + f[0] * size0.x / 2, ctr0.y + f[1] * size0.y / 2, ctr0.z + f[2] * size0.z / 2);
      testSphere.visible = $('sphere').checked;
      if (!testSphere.visible || !glgNow) return;
      const pos = sg.attributes.position, nor = sg.attributes.normal, col = sg.attributes.lbkColor;
      let hint = 0;
      for (let v = 0; v < pos.count; v++) {
        const p = [pos.getX(v) + testSphere.position.x, pos.getY(v) + testSphere.position.y, pos.getZ(v) + testSphere.position.z];
        col.array.set(shIrradiance(glgSample(glgNow, p, hint), 0, [nor.getX(v), nor.getY(v), nor.getZ(v)]), 3 * v);
      }
      col.needsUpdate = true;
    };
    const camera = new THREE.PerspectiveCamera(50, w / h, 0.01, 1e5);
    const controls = new THREE.OrbitControls(camera, renderer.domElement);
    if (P.cam) {
      const c = P.cam.split(',').map(Number);
      camera.position.set(c[0], c[1], c[2]); camera.up.set(c[6], c[7], c[8]); camera.fov = c[9];
      controls.target.set(c[3], c[4], c[5]);
    } else {
      const ctr = box.getCenter(new THREE.Vector3()), size = box.getSize(new THREE.Vector3());
      camera.position.copy(ctr).add(new THREE.Vector3(0, 0, size.length() * 0.9));
      controls.target.copy(ctr);
    }
    const far = box.getSize(new THREE.Vector3()).length() * 4 + camera.position.distanceTo(controls.target);
    camera.near = far * 1e-5; camera.far = far;
    camera.updateProjectionMatrix();
    controls.update();

    /* default exposure: 1 / (99th percentile of the lit texels' radiance for albedo 1), like lbk render's PNG */
    let defaultStops = 0;
    if (lastOut.z) {
      const lin = new Float32Array(12), vals = [];
      for (let t = 0; t < lastOut.z.length; t++) {
        LbkReader.ahdToLinear(lastOut.z[t], lastOut.rgba.subarray(4 * t, 4 * t + 4), lin, 0);
        const l = (0.2126 * (lin[0] + lin[3]) + 0.7152 * (lin[4] + lin[7]) + 0.0722 * (lin[8] + lin[11])) * lmap.scale;
        if (l > 0) vals.push(l / Math.PI);
      }
      /* block pages: their decoded linear forms (physical units already) */
      (lmap ? lmap.pages : []).forEach((pg, i) => {
        if (!pages[i] || !pages[i].block) return;
        const L = LbkReader.pageLinear(lmap, i);
        for (let t = 0; t < pg.width * pg.height; t++) {
          const l = 0.2126 * (L[12 * t] + L[12 * t + 3]) + 0.7152 * (L[12 * t + 4] + L[12 * t + 7]) + 0.0722 * (L[12 * t + 8] + L[12 * t + 11]);
          if (l > 0) vals.push(l / Math.PI);
        }
      });
      vals.sort((x, y) => x - y);
      if (vals.length) defaultStops = -Math.log2(vals[Math.floor(0.99 * (vals.length - 1))]);
    }
    const stops = P.stops !== undefined ? Number(P.stops) : Math.round(defaultStops * 10) / 10;
    $('exposure').value = String(stops);
    if (P.mode !== undefined) $('mode').value = P.mode;
    for (const k of (P.show || '').split(',')) { /* show=glg,llg,octp,sphere */
      const id = { glg: 'probes', llg: 'probes-llg', octp: 'probes-octp', sphere: 'sphere' }[k];
      if (id) $(id).checked = true;
    }
    if (P.sphere) P.sphere.split(',').forEach((v, i) => { $(['sx', 'sy', 'sz'][i]).value = v; });
    const apply = () => {
      uniformsCommon.exposure.value = Math.pow(2, Number($('exposure').value));
      $('exposure-v').textContent = Number($('exposure').value).toFixed(1);
      uniformsCommon.mode.value = Number($('mode').value);
      legend(Number($('mode').value) === 5);
      for (const [k, id] of [['glg', 'probes'], ['llg', 'probes-llg'], ['octp', 'probes-octp']]) if (groups[k]) groups[k].visible = $(id).checked;
      placeSphere();
      draw();
    };
    const draw = () => renderer.render(scene, camera);
    /* the error mode's legend (a colour bar in %), or why there is nothing to show */
    const legend = (on) => {
      const el = $('legend');
      el.style.display = on ? 'block' : 'none';
      if (!on) return;
      if (!emap) { el.innerHTML = '<b>no per-texel error map in this file</b>: bake with --error-map (lbk bake … --error-map)'; return; }
      let est = 0; for (let i = 0; i < emap.codes.length; i++) est += emap.codes[i] !== 0;
      const stops = ['rgb(13,38,153)', 'rgb(0,140,230)', 'rgb(26,204,77)', 'rgb(242,217,26)', 'rgb(217,26,26)'];
      el.innerHTML = 'relative standard error of the irradiance, per texel' + (emap.denoised ? ' (before denoising)' : '') +
        `<div class="bar" style="background:linear-gradient(to right,${stops.join(',')})"></div>` +
        '<div class="ticks"><span>0.1 %</span><span>1 %</span><span>10 %</span><span>≥ 100 %</span></div>' +
        `grey: no estimate; ${est.toLocaleString('en-US')} of ${emap.texel_count.toLocaleString('en-US')} texels estimated`;
    };
    for (const id of ['exposure', 'mode', 'probes', 'probes-llg', 'probes-octp', 'sphere', 'sx', 'sy', 'sz']) $(id).addEventListener('input', apply);
    $('sets').addEventListener('input', () => { applySets(); buildGlyphs(); placeSphere(); draw(); });
    $('footprint-set').addEventListener('input', () => { footprint(); draw(); });
    controls.addEventListener('change', draw);
    window.addEventListener('resize', () => {
      if (P.size) return;
      renderer.setSize(wrap.clientWidth, wrap.clientHeight);
      camera.aspect = wrap.clientWidth / wrap.clientHeight; camera.updateProjectionMatrix(); draw();
    });
    apply();
    status(data.name || 'level');
    window.lbkViewReady = true;
    document.title = 'lbk view: ready, ' + window.lbkErrors.length + ' errors';
  }

  function fmt(n) { return n.toLocaleString('en-US'); }
  const esc = (t) => String(t).replace(/[&<>"]/g, (c) => ({ '&': '&amp;', '<': '&lt;', '>': '&gt;', '"': '&quot;' }[c]));
  function plot(xs, ys, xlabel) {
    const cv = $('plot'), ctx = cv.getContext('2d');
    ctx.clearRect(0, 0, cv.width, cv.height);
    const xmax = Math.max(...xs, 1e-9), ymax = Math.max(...ys, 1e-9);
    ctx.strokeStyle = '#9cf'; ctx.beginPath();
    xs.forEach((x, i) => { const X = 30 + x / xmax * (cv.width - 40), Y = cv.height - 20 - ys[i] / ymax * (cv.height - 30); i ? ctx.lineTo(X, Y) : ctx.moveTo(X, Y); });
    ctx.stroke();
    ctx.fillStyle = '#aaa'; ctx.font = '10px sans-serif';
    ctx.fillText(ymax.toPrecision(3), 2, 12); ctx.fillText('0', 22, cv.height - 8);
    ctx.fillText(xmax.toPrecision(3) + ' ' + xlabel, cv.width - 110, cv.height - 5);
  }
  /* The panel: lbk inspect --json's numbers when lbk view embedded them (else the page's own
   * reader's section sizes), the level, and the error curve (the bake's JSON report against wall
   * clock when given, else REPT against samples per texel). */
  function panel(data, lbk, meta, rept, objs, lmap, glg) {
    const I = data.inspect;
    if (I && I.schema === 'lbk-inspect/1') {
      const rows = I.sections.map((s) => `<tr><td>${esc(s.type)}</td><td class="n">${fmt(s.disk_bytes)}</td><td class="n">${fmt(s.decoded_bytes)}</td><td class="n">${fmt(s.gpu_bytes)}</td></tr>`);
      const t = I.totals || {}, L = I.level || {};
      $('sections').innerHTML = '<tr><td>lbk inspect</td><td class="n">disk</td><td class="n">decoded</td><td class="n">GPU</td></tr>' + rows.join('') +
        `<tr><td>total</td><td class="n">${fmt(t.disk_bytes || 0)}</td><td class="n">${fmt(t.decoded_bytes || 0)}</td><td class="n">${fmt(t.gpu_bytes || 0)}</td></tr>` +
        `<tr><td colspan="3">GPU memory without / with DLS</td><td class="n">${fmt(L.memory_without_dls_bytes || 0)}<br>${fmt(L.memory_with_dls_bytes || 0)}</td></tr>` +
        (I.objects || []).map((o) => `<tr><td colspan="2">${esc(o.name)}</td><td class="n">${fmt(o.texels)} texels</td><td class="n">${fmt(o.total_bytes)}</td></tr>`).join('');
    } else {
      const rows = lbk.sections.map((s) => `<tr><td>${esc(s.type)}</td><td class="n">${fmt(s.stored_size)}</td><td class="n">${fmt(s.decoded_size)}</td><td>${s.compression ? 'zstd' : ''}</td></tr>`);
      const total = lbk.sections.reduce((a, s) => a + s.decoded_size, 0);
      $('sections').innerHTML = '<tr><td></td><td class="n">file</td><td class="n">decoded</td><td></td></tr>' + rows.join('') +
        `<tr><td>total</td><td class="n">${fmt(lbk.file_size)}</td><td class="n">${fmt(total)}</td><td></td></tr>`;
    }
    const lit = objs ? objs.filter((o) => o.representation === 'lightmap').length : 0;
    $('level').innerHTML = `format ${lbk.version.join('.')}; ${objs ? objs.length : 0} objects (${lit} lightmapped)` +
      (lmap ? `; ${lmap.pages.length} page(s), ${fmt(lmap.texel_count)} texels` : '') + (glg ? `; ${glg.probe_count} GLG probes` : '') +
      (meta && meta['scene.name'] ? `<br>scene ${esc(meta['scene.name'])}` : '') + (meta && meta['bake.preset'] ? `, preset ${esc(meta['bake.preset'])}` : '');
    const J = data.report;
    if (J && J.schema === 'lbk-bake-report/1' && Array.isArray(J.samples) && J.samples.length) {
      plot(J.samples.map((x) => x.seconds), J.samples.map((x) => x.est_rel_rmse), 's');
      const e = J.errors || {};
      $('report').innerHTML = `bake report: ${esc(J.status)}; ${J.samples.length} passes in ${(J.transport && J.transport.seconds || 0).toPrecision(3)} s; ` +
        `final rel. RMSE texels ${Number(e.texels || 0).toPrecision(3)}, probes ${Number(e.probes || 0).toPrecision(3)}` +
        (J.phases ? '<br>' + J.phases.map((p) => `${esc(p.name)} ${Number(p.seconds).toPrecision(2)} s`).join(', ') : '');
      return;
    }
    if (!rept) { $('report').textContent = 'no REPT section'; return; }
    const r = rept.records;
    plot(r.map((x) => rept.has_times ? x.elapsed_seconds : x.samples_per_texel), r.map((x) => x.texel_rel_rmse), rept.has_times ? 's' : 'samples/texel');
    const last = r[r.length - 1];
    $('report').innerHTML = `REPT: ${rept.status}; ${r.length} passes; last: ${last.samples_per_texel} samples/texel, texel rel. RMSE ${last.texel_rel_rmse.toPrecision(3)}, probe ${last.probe_rel_rmse.toPrecision(3)}`;
  }

  main().catch(fail);
})();
