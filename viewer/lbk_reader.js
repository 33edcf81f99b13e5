/* A reader of the lbk container (format 1.x), written from spec/container.md alone: the second,
 * independent reader of the format (the viewer's, and a conformance check of the spec: the node
 * test compares what it decodes with liblbk bit for bit).
 *
 * Float arithmetic follows the spec's decoders operation by operation in binary32: every
 * operation is rounded with Math.fround. For +, −, ×, ÷ and √ of binary32 operands, computing in
 * binary64 and rounding once to binary32 gives the correctly rounded binary32 result (53 ≥ 2·24+2),
 * so these are exactly the C decoders' values.
 *
 * Dependencies are passed in (no globals, no I/O): `decompress(u8, size)` returns one zstd frame's
 * bytes (fzstd), `xxh3(u8)` returns the XXH3-64 of the bytes as 16 hex digits (hash-wasm; it may
 * return a Promise). Works as a browser script (window.LbkReader) and as a node module. */
(function (root, factory) {
  if (typeof module === 'object' && module.exports) module.exports = factory();
  else root.LbkReader = factory();
}(typeof self !== 'undefined' ? self : this, function () {
  'use strict';
  const f32 = Math.fround;
  const MAGIC = [0x89, 0x4c, 0x42, 0x4b, 0x0d, 0x0a, 0x1a, 0x0a];
  const FEATURE_ZSTD = 1, FEATURE_LMAP_BLOCK = 2;
  const KNOWN = ['META', 'REPT', 'OBJS', 'LMAP', 'GLG ', 'LLG ', 'DLS ', 'DOOR', 'OCTP'];
  const SQRT3 = f32(1.7320508075688772), SQRT5 = f32(2.2360679774997897);
  const BAND_SCALE = [f32(1), SQRT3, SQRT3, SQRT3, SQRT5, SQRT5, SQRT5, SQRT5, SQRT5];
  const UF11_MAX = 65024;
  /* The default decoded-bytes cap of §4.3 is min(4 GiB, 1024·file + 64 MiB); a browser tab holds
   * far less, so this reader caps at 1 GiB as well. */
  const DECODE_CAP = 1 << 30;

  class LbkError extends Error {}
  function fail(msg) { throw new LbkError(msg); }

  function fourcc(v) {
    return String.fromCharCode(v & 255, (v >>> 8) & 255, (v >>> 16) & 255, v >>> 24);
  }
  const align16 = (x) => Math.ceil(x / 16) * 16;

  /* u64 as a JS number; refuses values above 2^53 (no real file needs them) */
  function u64(dv, o) {
    const lo = dv.getUint32(o, true), hi = dv.getUint32(o + 4, true);
    if (hi >= 0x200000) fail('a 64-bit size at ' + o + ' is beyond 2^53');
    return hi * 4294967296 + lo;
  }
  function hex64(dv, o) {
    return dv.getUint32(o + 4, true).toString(16).padStart(8, '0') +
           dv.getUint32(o, true).toString(16).padStart(8, '0');
  }
  function checkZero(u8, from, to, what) {
    for (let i = from; i < to; i++) if (u8[i] !== 0) fail(what + ': non-zero padding or reserved byte at ' + i);
  }
  function finite(x, what) { if (!Number.isFinite(x)) fail(what + ' is not finite'); return x; }

  /* ---- shared encodings (§5) ------------------------------------------------------------- */
  function smallDecode(code, mbits) {
    const e = code >>> mbits, m = code & ((1 << mbits) - 1);
    if (e === 0) return f32(m * Math.pow(2, -14 - mbits));
    if (e === 31) return m ? NaN : Infinity;
    return f32((1 + m / (1 << mbits)) * Math.pow(2, e - 15));
  }
  const uf11 = (c) => smallDecode(c & 0x7ff, 6);
  const uf10 = (c) => smallDecode(c & 0x3ff, 5);
  function r11g11b10f(w) { return [uf11(w), uf11(w >>> 11), uf10(w >>> 22)]; }
  function rgb9e5(w) {
    const e = (w >>> 27) - 24, s = Math.pow(2, e);
    return [f32((w & 0x1ff) * s), f32(((w >>> 9) & 0x1ff) * s), f32(((w >>> 18) & 0x1ff) * s)];
  }
  function half(h) {
    const m = smallDecode(h & 0x7fff, 10);
    return (h & 0x8000) ? -m : m;
  }
  const unorm8 = (c) => f32(c / 255);
  function snorm8(c) {
    const v = f32((c << 24 >> 24) / 127);
    return v < -1 ? -1 : v;
  }

  /* SH9 radiance probe (§5.5): 27 floats, channel-major [ch·9 + k], in stored units × scale */
  function sh9Unpack(u8, o, scale) {
    const w = u8[o] | (u8[o + 1] << 8) | (u8[o + 2] << 16) | (u8[o + 3] << 24);
    const dc = rgb9e5(w >>> 0);
    const out = new Float32Array(27);
    for (let c = 0; c < 3; c++) {
      out[c * 9] = f32(dc[c] * scale);
      for (let k = 1; k < 9; k++) {
        const q = snorm8(u8[o + 4 + 3 * (k - 1) + c]);
        out[c * 9 + k] = f32(f32(f32(q * BAND_SCALE[k]) * dc[c]) * scale);
      }
    }
    return out;
  }

  /* AHD texel (§5.6) to its linear form: 12 floats [ch·4 + {e0, gx, gy, gz}], stored units */
  function ahdDirection(g, b, a) {
    const x = f32(f32(f32(2 * g) / 255) - 1), y = f32(f32(f32(2 * b) / 255) - 1), z = f32(a / 255);
    const len = f32(Math.sqrt(f32(f32(f32(x * x) + f32(y * y)) + f32(z * z))));
    if (len < 0.5) return [0, 0, 1];
    return [f32(x / len), f32(y / len), f32(z / len)];
  }
  function ahdToLinear(ezWord, rgba, out, o) {
    const ez = r11g11b10f(ezWord);
    const d = ahdDirection(rgba[1], rgba[2], rgba[3]);
    const r = unorm8(rgba[0]);
    const k = f32(0.25 + f32(0.5 * d[2]));
    for (let c = 0; c < 3; c++) {
      let e = ez[c];
      if (e !== e) e = 0;
      if (e > UF11_MAX) e = UF11_MAX;
      const amb = f32(r * e);
      const inten = f32(f32(f32(1 - r) * e) / k);
      out[o + c * 4] = f32(amb + f32(0.25 * inten));
      for (let i = 0; i < 3; i++) out[o + c * 4 + 1 + i] = f32(f32(0.5 * inten) * d[i]);
    }
  }
  /* Irradiance for a unit tangent-space normal n: max(0, e0 + g·n) per channel */
  function linearEval(lin, o, n) {
    const rgb = [0, 0, 0];
    for (let c = 0; c < 3; c++) {
      const p = o + c * 4;
      const e = f32(f32(f32(lin[p] + f32(lin[p + 1] * n[0])) + f32(lin[p + 2] * n[1])) + f32(lin[p + 3] * n[2]));
      rgb[c] = e > 0 ? e : 0;
    }
    return rgb;
  }

  function checkScale(s, what) {
    const b = new DataView(new Float32Array([s]).buffer).getUint32(0, true);
    const e = (b >>> 23) & 255;
    if ((b >>> 31) || (b & 0x7fffff) || e === 0 || e === 255) fail(what + ': scale ' + s + ' is not a positive normal power of two');
    return s;
  }

  /* ---- container (§2, §3, §4) -------------------------------------------------------------- */
  async function open(bytes, deps) {
    const u8 = bytes instanceof Uint8Array ? bytes : new Uint8Array(bytes);
    const dv = new DataView(u8.buffer, u8.byteOffset, u8.byteLength);
    const size = u8.length;
    if (size < 64) fail('file too small for a header (' + size + ' bytes)');
    for (let i = 0; i < 8; i++) if (u8[i] !== MAGIC[i]) fail('not an lbk file (bad magic)');
    const major = dv.getUint16(8, true), minor = dv.getUint16(10, true);
    if (major !== 1) fail('format major version ' + major + ' is not known (this reader reads 1.x)');
    if (await deps.xxh3(u8.subarray(0, 56)) !== hex64(dv, 56)) fail('header checksum mismatch');
    if (dv.getUint32(12, true) !== 64) fail('header_size is not 64');
    const fileSize = u64(dv, 16);
    if (fileSize !== size) fail('file_size ' + fileSize + ' but the file has ' + size + ' bytes' + (fileSize > size ? ' (truncated)' : ' (bytes appended)'));
    const req = dv.getUint32(24, true);
    if (req & ~(FEATURE_ZSTD | FEATURE_LMAP_BLOCK)) fail('unknown required feature bits 0x' + req.toString(16));
    const count = dv.getUint32(32, true);
    if (count < 1 || count > 64) fail('section_count ' + count + ' outside 1..64');
    const align = dv.getUint32(36, true);
    if (align < 16 || align > 65536 || (align & (align - 1))) fail('section_alignment ' + align + ' is not a power of two in 16..65536');
    if (u64(dv, 40) !== 64) fail('section_table_offset is not 64');
    const tableEnd = 64 + 48 * count;
    if (tableEnd > size) fail('section table beyond the end of the file');
    if (await deps.xxh3(u8.subarray(64, tableEnd)) !== hex64(dv, 48)) fail('section table checksum mismatch');

    const sections = [];
    let pos = Math.ceil(tableEnd / align) * align, prevRank = -1, prevCode = -1, anyZstd = false;
    checkZero(u8, tableEnd, Math.min(pos, size), 'gap after the table');
    for (let i = 0; i < count; i++) {
      const e = 64 + 48 * i;
      const code = dv.getUint32(e, true), type = fourcc(code);
      for (let k = 0; k < 4; k++) { const ch = type.charCodeAt(k); if (ch < 0x20 || ch > 0x7e) fail('section ' + i + ': type is not printable ASCII'); }
      const flags = dv.getUint32(e + 4, true), comp = dv.getUint32(e + 8, true);
      if (flags & ~1) fail(type + ': unknown flags');
      if (comp > 1) fail(type + ': unknown compression ' + comp);
      if (dv.getUint32(e + 12, true) !== 0) fail(type + ': reserved field not 0');
      const offset = u64(dv, e + 16), stored = u64(dv, e + 24), decoded = u64(dv, e + 32);
      if (stored < 1) fail(type + ': stored_size 0');
      if (comp === 0 && decoded !== stored) fail(type + ': decoded_size differs from stored_size of an uncompressed section');
      if (comp === 1 && decoded < 1) fail(type + ': decoded_size 0');
      /* canonical order: the 1.0 types by rank, then every other type by ascending code */
      const rank = KNOWN.indexOf(type);
      const key = rank >= 0 ? rank : 100;
      if (key < prevRank || (key === prevRank && (key < 100 || code <= prevCode))) fail(type + ': sections out of canonical order or repeated');
      prevRank = key; prevCode = code;
      if (offset !== pos) fail(type + ': offset ' + offset + ' is not the placement ' + pos + ' (§3.3)');
      if (offset + stored > size) fail(type + ': section beyond the end of the file');
      const next = i + 1 < count ? Math.ceil((offset + stored) / align) * align : offset + stored;
      checkZero(u8, offset + stored, Math.min(next, size), type + ' padding');
      if (i + 1 === count && offset + stored !== size) fail('the last section does not end at file_size');
      pos = next;
      if (comp === 1) anyZstd = true;
      sections.push({ type, code, required: !!(flags & 1), compression: comp, offset, stored_size: stored,
                      decoded_size: decoded, checksum: hex64(dv, e + 40) });
    }
    if (anyZstd !== !!(req & FEATURE_ZSTD)) fail('the ZSTD feature bit does not match the sections');
    for (const s of sections)
      if (KNOWN.indexOf(s.type) < 0 && s.type !== 'LMUV' && s.type !== 'TERR' && s.required) fail('unknown required section ' + s.type);

    let charged = 0;
    const cache = new Map();
    /* §15.4: the section's bytes, checksum verified, zstd decoded within the cap */
    async function payload(type) {
      if (cache.has(type)) return cache.get(type);
      const s = sections.find((x) => x.type === type);
      if (!s) return null;
      const stored = u8.subarray(s.offset, s.offset + s.stored_size);
      if (await deps.xxh3(stored) !== s.checksum) fail(type + ': section checksum mismatch');
      let out = stored;
      if (s.compression === 1) {
        if (charged + s.decoded_size > DECODE_CAP) fail(type + ': decoded size over the cap');
        charged += s.decoded_size;
        out = deps.decompress(stored, s.decoded_size);
        if (out.length !== s.decoded_size) fail(type + ': decompressed ' + out.length + ' bytes, decoded_size ' + s.decoded_size);
      }
      const copy = new Uint8Array(out.length); copy.set(out); /* aligned, own buffer */
      cache.set(type, copy);
      return copy;
    }
    return { version: [major, minor], required_features: req, section_alignment: align, file_size: size,
             sections, payload,
             meta: async () => parseMeta(await payload('META')),
             report: async () => parseReport(await payload('REPT')),
             objects: async () => parseObjects(await payload('OBJS')),
             lightmap: async () => parseLightmap(await payload('LMAP')),
             glg: async () => parseGlg(await payload('GLG ')),
             llg: async () => parseLlg(await payload('LLG ')),
             octp: async () => parseOctp(await payload('OCTP')),
             errorMap: async () => parseErrorMap(await payload('TERR')),
             dls: async () => parseDls(await payload('DLS ')),
             doors: async () => parseDoor(await payload('DOOR')) };
  }

  function view(p) { return new DataView(p.buffer, p.byteOffset, p.byteLength); }
  function need(p, n, what) { if (n > p.length) fail(what + ': ' + n + ' bytes needed, section has ' + p.length); }
  const utf8 = new TextDecoder('utf-8', { fatal: true });

  /* ---- META (§6), REPT (§7), OBJS (§8) ------------------------------------------------------ */
  function parseMeta(p) {
    if (!p) return null;
    const dv = view(p); need(p, 16, 'META');
    const n = dv.getUint32(0, true), sz = dv.getUint32(4, true);
    checkZero(p, 8, 16, 'META');
    if (16 + 16 * n + sz !== p.length) fail('META: size does not match its counts');
    const blob = 16 + 16 * n, out = {};
    for (let i = 0; i < n; i++) {
      const e = 16 + 16 * i;
      const ko = dv.getUint32(e, true), kl = dv.getUint32(e + 4, true), vo = dv.getUint32(e + 8, true), vl = dv.getUint32(e + 12, true);
      if (ko + kl > sz || vo + vl > sz) fail('META: string outside the blob');
      out[utf8.decode(p.subarray(blob + ko, blob + ko + kl))] = utf8.decode(p.subarray(blob + vo, blob + vo + vl));
    }
    return out;
  }
  function parseReport(p) {
    if (!p) return null;
    const dv = view(p); need(p, 32, 'REPT');
    const n = dv.getUint32(8, true);
    if (32 + 32 * n !== p.length) fail('REPT: size does not match record_count');
    const recs = [];
    for (let i = 0; i < n; i++) {
      const o = 32 + 32 * i;
      recs.push({ elapsed_seconds: dv.getFloat64(o, true), rays_traced: u64(dv, o + 8),
                  samples_per_texel: dv.getUint32(o + 16, true), bounces: dv.getUint32(o + 20, true),
                  texel_rel_rmse: dv.getFloat32(o + 24, true), probe_rel_rmse: dv.getFloat32(o + 28, true) });
    }
    const status = ['converged', 'target reached', 'time limit', 'sample limit'][dv.getUint32(0, true)] || 'unknown';
    return { status, has_times: !!(dv.getUint32(4, true) & 1), max_samples_per_texel: dv.getUint32(12, true),
             time_limit_seconds: dv.getFloat64(16, true), target_rel_rmse: dv.getFloat32(24, true), records: recs };
  }
  function parseObjects(p) {
    if (!p) return null;
    const dv = view(p); need(p, 16, 'OBJS');
    const n = dv.getUint32(0, true), sz = dv.getUint32(4, true);
    checkZero(p, 8, 16, 'OBJS');
    if (16 + 40 * n + sz !== p.length) fail('OBJS: size does not match its counts');
    const blob = 16 + 40 * n, out = [];
    for (let i = 0; i < n; i++) {
      const o = 16 + 40 * i, no = dv.getUint32(o, true), nl = dv.getUint32(o + 4, true);
      if (no + nl > sz) fail('OBJS: name outside the blob');
      out.push({ name: utf8.decode(p.subarray(blob + no, blob + no + nl)), geometry_hash: hex64(dv, o + 8),
                 representation: ['lightmap', 'llg', 'none'][dv.getUint32(o + 16, true)] || fail('OBJS: representation'),
                 index: dv.getUint32(o + 20, true), rect: [dv.getUint32(o + 24, true), dv.getUint32(o + 28, true),
                 dv.getUint32(o + 32, true), dv.getUint32(o + 36, true)] });
    }
    return out;
  }

  /* ---- LMAP (§9) ---------------------------------------------------------------------------- */
  function planeSize(plane, fmt, w, h) {
    const nb = (w / 4) * (h / 4);
    if (fmt === 0) return 4 * w * h;
    if (plane === 0 && (fmt === 1 || fmt === 2)) return 16 * nb;
    if (plane === 1 && fmt === 1) return 24 * nb;
    if (plane === 1 && fmt === 2) return 16 * nb;
    fail('LMAP: undefined plane format ' + fmt);
  }
  function parseLightmap(p) {
    if (!p) return null;
    const dv = view(p); need(p, 16, 'LMAP');
    const n = dv.getUint32(0, true), scale = checkScale(dv.getFloat32(4, true), 'LMAP');
    need(p, 16 + 32 * n, 'LMAP page table');
    let pos = 16 + 32 * n, first = 0;
    const pages = [];
    for (let i = 0; i < n; i++) {
      const e = 16 + 32 * i, w = dv.getUint16(e, true), h = dv.getUint16(e + 2, true), enc = dv.getUint32(e + 4, true);
      if (w < 1 || h < 1 || w > 16384 || h > 16384) fail('LMAP page ' + i + ': size ' + w + 'x' + h);
      if (enc >>> 16) fail('LMAP page ' + i + ': reserved encoding bits');
      const f0 = enc & 255, f1 = (enc >>> 8) & 255;
      if ((f0 || f1) && (w % 4 || h % 4)) fail('LMAP page ' + i + ': a block page needs sizes in multiples of 4');
      if (u64(dv, e + 8) !== first) fail('LMAP page ' + i + ': first_texel');
      const p0 = align16(pos), s0 = planeSize(0, f0, w, h), p1 = align16(p0 + s0), s1 = planeSize(1, f1, w, h);
      if (u64(dv, e + 16) !== p0 || u64(dv, e + 24) !== p1) fail('LMAP page ' + i + ': plane offsets are not the layout of §9.1');
      checkZero(p, pos, p0, 'LMAP'); checkZero(p, p0 + s0, p1, 'LMAP');
      pos = p1 + s1; need(p, pos, 'LMAP planes');
      pages.push({ width: w, height: h, format0: f0, format1: f1, first_texel: first,
                   plane0: p.subarray(p0, p0 + s0), plane1: p.subarray(p1, p1 + s1) });
      first += w * h;
    }
    if (pos !== p.length) fail('LMAP: section does not end after the last plane');
    if (u64(dv, 8) !== first) fail('LMAP: texel_count');
    return { scale, texel_count: first, pages };
  }
  /* Page i's texels as linear forms (12 floats each, physical units: × scale): 1.0 pages by
   * §5.6 from the stored words, block pages (BC6H, BC5 + BC4; §9.2) through the float texel form
   * as liblbk's lbk_lmap_planes_texel_unpack. ASTC pages: an error (no ASTC decoder here). */
  function pageLinear(lmap, i) {
    const pg = lmap.pages[i];
    const n = pg.width * pg.height, out = new Float32Array(12 * n);
    if (pg.format0 || pg.format1) {
      const tf = pageTexelsF(pg);
      for (let t = 0; t < n; t++) texelFToLinear(tf, 7 * t, out, 12 * t);
    } else {
      const d0 = view(pg.plane0);
      for (let t = 0; t < n; t++) ahdToLinear(d0.getUint32(4 * t, true), pg.plane1.subarray(4 * t, 4 * t + 4), out, 12 * t);
    }
    for (let k = 0; k < 12 * n; k++) out[k] = f32(out[k] * lmap.scale);
    return out;
  }

  /* ---- block-encoded LMAP planes (§9.2): BC6H_UF16, BC4, BC5 ---------------------------------- */
  /* BC6H unsigned (the D3D11 decoding, all 14 modes). A mode's fields are (endpoint component,
   * first bit, bit count, reversed) in the order the block stores them, LSB first; components
   * 0–11 are w, x, y, z of R, G, B (w/x region 0, y/z region 1), 12 the partition. */
  const [RW, GW, BW, RX, GX, BX, RY, GY, BY, RZ, GZ, BZ, D] = [0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12];
  const F = (w, a, n) => [w, a, n, 0], RV = (w, a, n) => [w, a, n, 1];
  /* [code, code bits, regions, transformed, w, dr, dg, db, fields] */
  const BC6H_MODES = [
    [0x00, 2, 2, 1, 10, 5, 5, 5, [F(GY, 4, 1), F(BY, 4, 1), F(BZ, 4, 1), F(RW, 0, 10), F(GW, 0, 10), F(BW, 0, 10), F(RX, 0, 5), F(GZ, 4, 1),
      F(GY, 0, 4), F(GX, 0, 5), F(BZ, 0, 1), F(GZ, 0, 4), F(BX, 0, 5), F(BZ, 1, 1), F(BY, 0, 4), F(RY, 0, 5),
      F(BZ, 2, 1), F(RZ, 0, 5), F(BZ, 3, 1), F(D, 0, 5)]],
    [0x01, 2, 2, 1, 7, 6, 6, 6, [F(GY, 5, 1), F(GZ, 4, 1), F(GZ, 5, 1), F(RW, 0, 7), F(BZ, 0, 1), F(BZ, 1, 1), F(BY, 4, 1), F(GW, 0, 7),
      F(BY, 5, 1), F(BZ, 2, 1), F(GY, 4, 1), F(BW, 0, 7), F(BZ, 3, 1), F(BZ, 5, 1), F(BZ, 4, 1), F(RX, 0, 6),
      F(GY, 0, 4), F(GX, 0, 6), F(GZ, 0, 4), F(BX, 0, 6), F(BY, 0, 4), F(RY, 0, 6), F(RZ, 0, 6), F(D, 0, 5)]],
    [0x02, 5, 2, 1, 11, 5, 4, 4, [F(RW, 0, 10), F(GW, 0, 10), F(BW, 0, 10), F(RX, 0, 5), F(RW, 10, 1), F(GY, 0, 4), F(GX, 0, 4), F(GW, 10, 1),
      F(BZ, 0, 1), F(GZ, 0, 4), F(BX, 0, 4), F(BW, 10, 1), F(BZ, 1, 1), F(BY, 0, 4), F(RY, 0, 5), F(BZ, 2, 1),
      F(RZ, 0, 5), F(BZ, 3, 1), F(D, 0, 5)]],
    [0x06, 5, 2, 1, 11, 4, 5, 4, [F(RW, 0, 10), F(GW, 0, 10), F(BW, 0, 10), F(RX, 0, 4), F(RW, 10, 1), F(GZ, 4, 1), F(GY, 0, 4), F(GX, 0, 5),
      F(GW, 10, 1), F(GZ, 0, 4), F(BX, 0, 4), F(BW, 10, 1), F(BZ, 1, 1), F(BY, 0, 4), F(RY, 0, 4), F(BZ, 0, 1),
      F(BZ, 2, 1), F(RZ, 0, 4), F(GY, 4, 1), F(BZ, 3, 1), F(D, 0, 5)]],
    [0x0a, 5, 2, 1, 11, 4, 4, 5, [F(RW, 0, 10), F(GW, 0, 10), F(BW, 0, 10), F(RX, 0, 4), F(RW, 10, 1), F(BY, 4, 1), F(GY, 0, 4), F(GX, 0, 4),
      F(GW, 10, 1), F(BZ, 0, 1), F(GZ, 0, 4), F(BX, 0, 5), F(BW, 10, 1), F(BY, 0, 4), F(RY, 0, 4), F(BZ, 1, 1),
      F(BZ, 2, 1), F(RZ, 0, 4), F(BZ, 4, 1), F(BZ, 3, 1), F(D, 0, 5)]],
    [0x0e, 5, 2, 1, 9, 5, 5, 5, [F(RW, 0, 9), F(BY, 4, 1), F(GW, 0, 9), F(GY, 4, 1), F(BW, 0, 9), F(BZ, 4, 1), F(RX, 0, 5), F(GZ, 4, 1),
      F(GY, 0, 4), F(GX, 0, 5), F(BZ, 0, 1), F(GZ, 0, 4), F(BX, 0, 5), F(BZ, 1, 1), F(BY, 0, 4), F(RY, 0, 5),
      F(BZ, 2, 1), F(RZ, 0, 5), F(BZ, 3, 1), F(D, 0, 5)]],
    [0x12, 5, 2, 1, 8, 6, 5, 5, [F(RW, 0, 8), F(GZ, 4, 1), F(BY, 4, 1), F(GW, 0, 8), F(BZ, 2, 1), F(GY, 4, 1), F(BW, 0, 8), F(BZ, 3, 1),
      F(BZ, 4, 1), F(RX, 0, 6), F(GY, 0, 4), F(GX, 0, 5), F(BZ, 0, 1), F(GZ, 0, 4), F(BX, 0, 5), F(BZ, 1, 1),
      F(BY, 0, 4), F(RY, 0, 6), F(RZ, 0, 6), F(D, 0, 5)]],
    [0x16, 5, 2, 1, 8, 5, 6, 5, [F(RW, 0, 8), F(BZ, 0, 1), F(BY, 4, 1), F(GW, 0, 8), F(GY, 5, 1), F(GY, 4, 1), F(BW, 0, 8), F(GZ, 5, 1),
      F(BZ, 4, 1), F(RX, 0, 5), F(GZ, 4, 1), F(GY, 0, 4), F(GX, 0, 6), F(GZ, 0, 4), F(BX, 0, 5), F(BZ, 1, 1),
      F(BY, 0, 4), F(RY, 0, 5), F(BZ, 2, 1), F(RZ, 0, 5), F(BZ, 3, 1), F(D, 0, 5)]],
    [0x1a, 5, 2, 1, 8, 5, 5, 6, [F(RW, 0, 8), F(BZ, 1, 1), F(BY, 4, 1), F(GW, 0, 8), F(BY, 5, 1), F(GY, 4, 1), F(BW, 0, 8), F(BZ, 5, 1),
      F(BZ, 4, 1), F(RX, 0, 5), F(GZ, 4, 1), F(GY, 0, 4), F(GX, 0, 5), F(BZ, 0, 1), F(GZ, 0, 4), F(BX, 0, 6),
      F(BY, 0, 4), F(RY, 0, 5), F(BZ, 2, 1), F(RZ, 0, 5), F(BZ, 3, 1), F(D, 0, 5)]],
    [0x1e, 5, 2, 0, 6, 6, 6, 6, [F(RW, 0, 6), F(GZ, 4, 1), F(BZ, 0, 1), F(BZ, 1, 1), F(BY, 4, 1), F(GW, 0, 6), F(GY, 5, 1), F(BY, 5, 1),
      F(BZ, 2, 1), F(GY, 4, 1), F(BW, 0, 6), F(GZ, 5, 1), F(BZ, 3, 1), F(BZ, 5, 1), F(BZ, 4, 1), F(RX, 0, 6),
      F(GY, 0, 4), F(GX, 0, 6), F(GZ, 0, 4), F(BX, 0, 6), F(BY, 0, 4), F(RY, 0, 6), F(RZ, 0, 6), F(D, 0, 5)]],
    [0x03, 5, 1, 0, 10, 10, 10, 10, [F(RW, 0, 10), F(GW, 0, 10), F(BW, 0, 10), F(RX, 0, 10), F(GX, 0, 10), F(BX, 0, 10)]],
    [0x07, 5, 1, 1, 11, 9, 9, 9, [F(RW, 0, 10), F(GW, 0, 10), F(BW, 0, 10), F(RX, 0, 9), F(RW, 10, 1), F(GX, 0, 9), F(GW, 10, 1), F(BX, 0, 9),
      F(BW, 10, 1)]],
    [0x0b, 5, 1, 1, 12, 8, 8, 8, [F(RW, 0, 10), F(GW, 0, 10), F(BW, 0, 10), F(RX, 0, 8), RV(RW, 10, 2), F(GX, 0, 8), RV(GW, 10, 2), F(BX, 0, 8),
      RV(BW, 10, 2)]],
    [0x0f, 5, 1, 1, 16, 4, 4, 4, [F(RW, 0, 10), F(GW, 0, 10), F(BW, 0, 10), F(RX, 0, 4), RV(RW, 10, 6), F(GX, 0, 4), RV(GW, 10, 6), F(BX, 0, 4),
      RV(BW, 10, 6)]],
  ];
  /* two-region shapes: bit t set = texel t in region 1; the anchor texel of region 1 */
  const BC6H_SHAPES = [0xcccc, 0x8888, 0xeeee, 0xecc8, 0xc880, 0xfeec, 0xfec8, 0xec80, 0xc800, 0xffec, 0xfe80,
    0xe800, 0xffe8, 0xff00, 0xfff0, 0xf000, 0xf710, 0x008e, 0x7100, 0x08ce, 0x008c, 0x7310,
    0x3100, 0x8cce, 0x088c, 0x3110, 0x6666, 0x366c, 0x17e8, 0x0ff0, 0x718e, 0x399c];
  const BC6H_ANCHOR = [15, 15, 15, 15, 15, 15, 15, 15, 15, 15, 15, 15, 15, 15, 15, 15,
    15, 2, 8, 2, 2, 8, 8, 15, 2, 8, 2, 2, 8, 8, 2, 2];
  const W3 = [0, 9, 18, 27, 37, 46, 55, 64], W4 = [0, 4, 9, 13, 17, 21, 26, 30, 34, 38, 43, 47, 51, 55, 60, 64];

  function bc6hUnquantize(v, bits) {
    if (bits >= 15 || v === 0) return v;
    if (v === (1 << bits) - 1) return 0xffff;
    return ((v << 16) + 0x8000) >>> bits;
  }
  /* 16 texels × RGB binary16 codes of the block at u8[o..o+16); reserved modes decode as 0 */
  function bc6hUnpack(u8, o, out) {
    let pos = 0;
    const take = (n) => { let v = 0; for (let i = 0; i < n; i++, pos++) v |= ((u8[o + (pos >> 3)] >> (pos & 7)) & 1) << i; return v; };
    let mode = -1;
    if ((u8[o] & 3) < 2) { mode = u8[o] & 3; pos = 2; }
    else { const five = u8[o] & 31; for (let m = 2; m < 14; m++) if (BC6H_MODES[m][0] === five) { mode = m; pos = 5; } }
    if (mode < 0) { out.fill(0); return false; }
    const [, , regions, transformed, wb, dr, dg, db, fields] = BC6H_MODES[mode];
    const comp = new Array(13).fill(0);
    for (const [what, first, count, rev] of fields) {
      const v = take(count);
      for (let i = 0; i < count; i++) comp[what] |= ((v >> i) & 1) << (rev ? first + count - 1 - i : first + i);
    }
    const nep = 2 * regions, dbits = [dr, dg, db], e = [[0, 0, 0], [0, 0, 0], [0, 0, 0], [0, 0, 0]];
    for (let c = 0; c < 3; c++) {
      e[0][c] = comp[RW + c];
      for (let k = 1; k < nep; k++) {
        const raw = comp[RW + 3 * k + c];
        if (transformed) {
          const sh = 32 - dbits[c], d = (raw << sh) >> sh;
          e[k][c] = (e[0][c] + d) & ((1 << wb) - 1);
        } else e[k][c] = raw;
      }
      for (let k = 0; k < nep; k++) e[k][c] = bc6hUnquantize(e[k][c], wb);
    }
    const shape = regions === 2 ? BC6H_SHAPES[comp[D]] : 0, anchor = regions === 2 ? BC6H_ANCHOR[comp[D]] : 16;
    const ib = regions === 2 ? 3 : 4, wt = regions === 2 ? W3 : W4;
    for (let t = 0; t < 16; t++) {
      const reg = (shape >> t) & 1, idx = take(t === 0 || t === anchor ? ib - 1 : ib);
      for (let c = 0; c < 3; c++) {
        const a = e[2 * reg][c], z = e[2 * reg + 1][c];
        const v = (a * (64 - wt[idx]) + z * wt[idx] + 32) >> 6;
        out[3 * t + c] = (v * 31) >> 6;
      }
    }
    return true;
  }
  /* BC4_UNORM block at u8[o..o+8) → 16 binary32 values */
  function bc4Unpack(u8, o, out) {
    const a = u8[o], b = u8[o + 1], pal = [f32(a / 255), f32(b / 255)];
    if (a > b) for (let i = 1; i < 7; i++) pal.push(f32(((7 - i) * a + i * b) / 1785));
    else { for (let i = 1; i < 5; i++) pal.push(f32(((5 - i) * a + i * b) / 1275)); pal.push(0, 1); }
    for (let t = 0; t < 16; t++) {
      const bit = 3 * t, byte = o + 2 + (bit >> 3), sh = bit & 7;
      const v = (u8[byte] | ((byte + 1 < o + 8 ? u8[byte + 1] : 0) << 8)) >> sh;
      out[t] = pal[v & 7];
    }
  }
  /* A page's texels in the float texel form of liblbk (lbk_ahd_texel_f: Ez RGB, then r, X, Y, Z
   * of plane 1 as channel values), 7 floats each, stored units; any encoding but ASTC. */
  function pageTexelsF(pg) {
    if (pg.format0 === 2 || pg.format1 === 2) fail('ASTC 4x4 pages are not decoded by this reader (no ASTC decoder in JS)');
    const w = pg.width, n = w * pg.height, out = new Float32Array(7 * n);
    const bx = w / 4, nb = bx * (pg.height / 4);
    const d0 = view(pg.plane0), h = new Array(48), dir0 = new Float32Array(16), dir1 = new Float32Array(16), rat = new Float32Array(16);
    for (let t = 0; t < n; t++) {
      if (pg.format0 === 0) {
        const ez = r11g11b10f(d0.getUint32(4 * t, true));
        for (let c = 0; c < 3; c++) { let e = ez[c]; if (e !== e) e = 0; if (e > UF11_MAX) e = UF11_MAX; out[7 * t + c] = e; }
      }
      if (pg.format1 === 0) for (let k = 0; k < 4; k++) out[7 * t + 3 + k] = unorm8(pg.plane1[4 * t + k]);
    }
    const bo = align16(16 * nb);
    for (let b = 0; b < (pg.format0 || pg.format1 ? nb : 0); b++) {
      const x0 = 4 * (b % bx), y0 = 4 * Math.floor(b / bx);
      if (pg.format0 === 1) bc6hUnpack(pg.plane0, 16 * b, h);
      if (pg.format1 === 1) { bc4Unpack(pg.plane1, 16 * b, dir0); bc4Unpack(pg.plane1, 16 * b + 8, dir1); bc4Unpack(pg.plane1, bo + 8 * b, rat); }
      for (let i = 0; i < 16; i++) {
        const o = 7 * ((y0 + (i >> 2)) * w + x0 + (i & 3));
        if (pg.format0 === 1) for (let c = 0; c < 3; c++) out[o + c] = half(h[3 * i + c]);
        if (pg.format1 === 1) {
          const dx = f32(f32(2 * dir0[i]) - 1), dy = f32(f32(2 * dir1[i]) - 1), zz = f32(f32(1 - f32(dx * dx)) - f32(dy * dy));
          out[o + 3] = rat[i]; out[o + 4] = dir0[i]; out[o + 5] = dir1[i]; out[o + 6] = zz > 0 ? f32(Math.sqrt(zz)) : 0;
        }
      }
    }
    return out;
  }
  /* lbk_ahd_texel_f_to_linear: 7 floats at t[o] → 12 floats at out[q] */
  function texelFToLinear(t, o, out, q) {
    const x = f32(f32(2 * t[o + 4]) - 1), y = f32(f32(2 * t[o + 5]) - 1), z = t[o + 6];
    const len = f32(Math.sqrt(f32(f32(f32(x * x) + f32(y * y)) + f32(z * z))));
    const d = len >= 0.5 ? [f32(x / len), f32(y / len), f32(z / len)] : [0, 0, 1];
    let r = t[o + 3];
    if (!(r >= 0)) r = 0;
    if (r > 1) r = 1;
    const k = f32(0.25 + f32(0.5 * d[2]));
    for (let c = 0; c < 3; c++) {
      let e = t[o + c];
      if (!(e >= 0)) e = 0;
      if (e > 65504) e = 65504;
      const amb = f32(r * e), inten = f32(f32(f32(1 - r) * e) / k);
      out[q + c * 4] = f32(amb + f32(0.25 * inten));
      for (let i = 0; i < 3; i++) out[q + c * 4 + 1 + i] = f32(f32(0.5 * inten) * d[i]);
    }
  }

  /* ---- TERR (§18, format 1.4): the per-texel error map ------------------------------------- */
  const TERR_CODE_ONE = 161, TERR_STEPS = 16, TERR_DENOISED = 1;
  function parseErrorMap(p) {
    if (!p) return null;
    const dv = view(p); need(p, 16, 'TERR');
    const enc = dv.getUint32(0, true), flags = dv.getUint32(4, true), n = u64(dv, 8);
    if (enc !== 0) fail('TERR: encoding ' + enc + ' is not defined');
    if (flags & ~TERR_DENOISED) fail('TERR: unknown flag bits');
    if (n < 1 || 16 + n !== p.length) fail('TERR: size does not match texel_count');
    return { texel_count: n, denoised: !!(flags & TERR_DENOISED), codes: p.subarray(16, 16 + n) };
  }
  /* relative standard error of a code (§18.2); -1: no estimate (code 0) */
  function errorOfCode(c) { return c === 0 ? -1 : Math.pow(2, (c - TERR_CODE_ONE) / TERR_STEPS); }

  /* ---- GLG (§10), LLG (§11), OCTP (§14) ------------------------------------------------------ */
  function parseGlg(p) {
    if (!p) return null;
    const dv = view(p); need(p, 32, 'GLG');
    const P = dv.getUint32(0, true), T = dv.getUint32(4, true), scale = checkScale(dv.getFloat32(8, true), 'GLG');
    checkZero(p, 12, 32, 'GLG');
    const oPos = 32, oPr = align16(oPos + 12 * P), oTe = align16(oPr + 28 * P), oAd = oTe + 16 * T, oVi = oAd + 16 * T;
    if (oVi + 4 * T !== p.length) fail('GLG: size does not match its counts');
    const positions = new Float32Array(3 * P), sh = new Float32Array(27 * P);
    for (let i = 0; i < P; i++) {
      for (let k = 0; k < 3; k++) positions[3 * i + k] = finite(dv.getFloat32(oPos + 12 * i + 4 * k, true), 'GLG position');
      sh.set(sh9Unpack(p, oPr + 28 * i, scale), 27 * i);
    }
    const tetras = new Uint32Array(4 * T), visibility = new Uint8Array(4 * T);
    for (let i = 0; i < 4 * T; i++) {
      tetras[i] = dv.getUint32(oTe + 4 * i, true);
      if (tetras[i] >= P) fail('GLG: tetra index out of range');
      visibility[i] = p[oVi + i];
    }
    return { probe_count: P, tetra_count: T, scale, positions, sh, tetras, visibility };
  }
  function parseLlg(p) {
    if (!p) return null;
    const dv = view(p); need(p, 32, 'LLG');
    const G = dv.getUint32(0, true), scale = checkScale(dv.getFloat32(4, true), 'LLG');
    const probeCount = u64(dv, 8), vertexCount = u64(dv, 16);
    checkZero(p, 24, 32, 'LLG');
    need(p, 32 + 96 * G, 'LLG grids');
    const oPr = align16(32 + 96 * G), oVe = align16(oPr + 28 * probeCount);
    if (oVe + 4 * vertexCount !== p.length) fail('LLG: size does not match its counts');
    const grids = [];
    let po = 0, vo = 0;
    for (let g = 0; g < G; g++) {
      const o = 32 + 96 * g, fl = (k) => finite(dv.getFloat32(o + 4 * k, true), 'LLG grid');
      const n = [dv.getUint16(o + 60, true), dv.getUint16(o + 62, true), dv.getUint16(o + 64, true)];
      if (u64(dv, o + 72) !== po || u64(dv, o + 80) !== vo) fail('LLG grid ' + g + ': offsets');
      const vc = dv.getUint32(o + 88, true), np = n[0] * n[1] * n[2];
      const sh = new Float32Array(27 * np);
      for (let i = 0; i < np; i++) sh.set(sh9Unpack(p, oPr + 28 * (po + i), scale), 27 * i);
      const vertices = p.subarray(oVe + 4 * vo, oVe + 4 * (vo + vc));
      grids.push({ centre: [fl(0), fl(1), fl(2)], axes: [[fl(3), fl(4), fl(5)], [fl(6), fl(7), fl(8)], [fl(9), fl(10), fl(11)]],
                   half_extents: [fl(12), fl(13), fl(14)], n, sh, vertex_count: vc, vertices });
      po += np; vo += vc;
    }
    if (po !== probeCount || vo !== vertexCount) fail('LLG: probe_count or vertex_count');
    return { scale, grids };
  }
  function parseOctp(p) {
    if (!p) return null;
    const dv = view(p); need(p, 16, 'OCTP');
    const n = dv.getUint32(0, true), scale = checkScale(dv.getFloat32(4, true), 'OCTP');
    /* level_count 0: a list of probes (1.0-1.2); 1-3: a probe volume (1.3, §14.1) */
    const L = dv.getUint32(8, true);
    if (L > 3) fail('OCTP: level_count ' + L + ' (at most 3)');
    checkZero(p, 12, 16, 'OCTP');
    const base = 16 + 48 * L;
    if (base + 1024 * n !== p.length) fail('OCTP: size does not match probe_count');
    const levels = [];
    let first = 0;
    for (let l = 0; l < L; l++) {
      const o = 16 + 48 * l;
      const lv = { origin: [dv.getFloat32(o, true), dv.getFloat32(o + 4, true), dv.getFloat32(o + 8, true)],
                   spacing: dv.getFloat32(o + 12, true),
                   dims: [dv.getUint32(o + 16, true), dv.getUint32(o + 20, true), dv.getUint32(o + 24, true)],
                   first_probe: dv.getUint32(o + 28, true), miss_distance: dv.getFloat32(o + 32, true) };
      checkZero(p, o + 36, o + 48, 'OCTP level ' + l);
      if (!(lv.spacing > 0) || (l > 0 && !(lv.spacing > levels[l - 1].spacing))) fail('OCTP level ' + l + ': spacing');
      if (lv.dims.some((d) => d < 2 || d > 256)) fail('OCTP level ' + l + ': dims');
      if (lv.first_probe !== first) fail('OCTP level ' + l + ': first_probe');
      first += lv.dims[0] * lv.dims[1] * lv.dims[2];
      levels.push(lv);
    }
    if (L && first !== n) fail('OCTP: probe_count is not the levels\' probes');
    const probes = [];
    for (let i = 0; i < n; i++) {
      const o = base + 1024 * i;
      /* the 4×4 interior, row-major (j·4 + i), physical */
      const irr = new Float32Array(48);
      for (let j = 0; j < 4; j++)
        for (let x = 0; x < 4; x++) {
          const c = r11g11b10f(dv.getUint32(o + 4 * ((j + 1) * 6 + x + 1), true));
          for (let ch = 0; ch < 3; ch++) irr[3 * (j * 4 + x) + ch] = f32(c[ch] * scale);
        }
      const full = new Float32Array(108); /* all 6 × 6 stored texels (the border too), physical */
      for (let t = 0; t < 36; t++) {
        const c = r11g11b10f(dv.getUint32(o + 4 * t, true));
        for (let ch = 0; ch < 3; ch++) full[3 * t + ch] = f32(c[ch] * scale);
      }
      const depth = new Float32Array(288);
      for (let j = 0; j < 12; j++)
        for (let x = 0; x < 12; x++)
          for (let m = 0; m < 2; m++) depth[2 * (j * 12 + x) + m] = half(dv.getUint16(o + 144 + 4 * ((j + 1) * 14 + x + 1) + 2 * m, true));
      const probe = { position: [dv.getFloat32(o + 928, true), dv.getFloat32(o + 932, true), dv.getFloat32(o + 936, true)], irradiance: irr,
                      irradiance_full: full, depth };
      if (L) {
        probe.offset = [dv.getFloat32(o + 940, true), dv.getFloat32(o + 944, true), dv.getFloat32(o + 948, true)];
        probe.state = dv.getUint32(o + 952, true); /* 0 active, 1 inside geometry (not light), 2 no nearby geometry */
        if (probe.state > 2) fail('OCTP probe ' + i + ': state ' + probe.state);
        probe.rays = dv.getUint32(o + 956, true);
        probe.backface = dv.getFloat32(o + 960, true);
        probe.nearest = dv.getFloat32(o + 964, true);
        checkZero(p, o + 968, o + 1024, 'OCTP probe ' + i);
      } else {
        checkZero(p, o + 940, o + 1024, 'OCTP probe ' + i);
      }
      probes.push(probe);
    }
    return { scale, levels, probes };
  }


  /* ---- encoders (§5.1–§5.6, as liblbk implements them: DLS apply re-encodes, §12.8) ------------ */
  const fbuf = new DataView(new ArrayBuffer(4));
  function fbits(x) { fbuf.setFloat32(0, x, true); return fbuf.getUint32(0, true); }
  /* round to nearest, ties to even, of a finite double */
  function rne(x) {
    const f = Math.floor(x), d = x - f;
    if (d > 0.5) return f + 1;
    if (d < 0.5) return f;
    return f % 2 === 0 ? f : f + 1;
  }
  function smallFromMagnitude(a, mbits) {
    const maxCode = ((30 << mbits) | ((1 << mbits) - 1)) >>> 0;
    const exp = a >>> 23;
    if (exp >= 113) {
      if (exp > 142) return maxCode;
      const shift = 23 - mbits;
      const t = (a - (112 << 23)) >>> 0;
      const r = ((t + ((1 << (shift - 1)) - 1) + ((t >>> shift) & 1)) >>> 0) >>> shift;
      return r > maxCode ? maxCode : r;
    }
    const sig = exp === 0 ? (a & 0x7fffff) : ((a & 0x7fffff) | 0x800000);
    const e = exp === 0 ? -126 : exp - 127;
    const rshift = 23 - 14 - mbits - e;
    if (rshift > 24) return 0;
    let q = rshift >= 32 ? 0 : sig >>> rshift;
    const rem = sig & ((1 << rshift) - 1), half = 1 << (rshift - 1);
    if (rem > half || (rem === half && (q & 1))) q++;
    return q;
  }
  function smallEncode(x, mbits) {
    const u = fbits(x);
    if ((u & 0x7fffffff) > 0x7f800000) return 0;
    if (u >>> 31) return 0;
    if (u === 0x7f800000) return ((30 << mbits) | ((1 << mbits) - 1)) >>> 0;
    return smallFromMagnitude(u, mbits);
  }
  function r11g11b10fPack(rgb) {
    return (smallEncode(rgb[0], 6) | (smallEncode(rgb[1], 6) << 11) | (smallEncode(rgb[2], 5) << 22)) >>> 0;
  }
  function unorm8Encode(x) {
    if (!(x > 0)) return 0;
    if (x >= 1) return 255;
    return rne(x * 255);
  }
  function snorm8Encode(x) {
    if (x !== x) return 0;
    if (x >= 1) return 127;
    if (x <= -1) return 0x81;
    return rne(x * 127) & 255;
  }
  function rgb9e5Pack(rgb) {
    const c = rgb.map((x) => (!(x > 0) ? 0 : Math.min(x, 65408)));
    const maxc = Math.max(c[0], c[1], c[2]);
    let es = 0;
    if (maxc > 0) {
      let e = Math.floor(Math.log2(maxc)); /* floor(log2 maxc), corrected where log2 rounds */
      if (Math.pow(2, e) > maxc) e--;
      if (Math.pow(2, e + 1) <= maxc) e++;
      es = (e < -16 ? -16 : e) + 16;
      if (rne(maxc * Math.pow(2, 24 - es)) >= 512) es++;
    }
    let out = es * 134217728; /* << 27 without the sign */
    for (let i = 0; i < 3; i++) out += rne(c[i] * Math.pow(2, 24 - es)) * Math.pow(2, 9 * i);
    return out >>> 0;
  }
  const LUM = [f32(0.2126), f32(0.7152), f32(0.0722)];
  const BIG = f32(1e30);
  function sanitize(x) { return x !== x ? 0 : x > BIG ? BIG : x < -BIG ? -BIG : x; }
  /* lbk_ahd_from_linear: lin = 12 floats [ch·4 + {e0, gx, gy, gz}] → [Ez word, r, G, B, A] */
  function ahdFromLinear(lin, o) {
    const e0 = [0, 0, 0], g = [[0, 0, 0], [0, 0, 0], [0, 0, 0]];
    for (let c = 0; c < 3; c++) {
      e0[c] = sanitize(lin[o + 4 * c]);
      for (let i = 0; i < 3; i++) g[c][i] = sanitize(lin[o + 4 * c + 1 + i]);
    }
    const sv = [0, 0, 0];
    for (let c = 0; c < 3; c++) for (let i = 0; i < 3; i++) sv[i] += LUM[c] * g[c][i];
    let dir = [0, 0, 1];
    const len = Math.sqrt(sv[0] * sv[0] + sv[1] * sv[1] + sv[2] * sv[2]);
    if (len >= 1e-30) {
      if (sv[2] >= 0) dir = [sv[0] / len, sv[1] / len, sv[2] / len];
      else {
        const lxy = Math.sqrt(sv[0] * sv[0] + sv[1] * sv[1]);
        if (lxy >= 1e-30) dir = [sv[0] / lxy, sv[1] / lxy, 0];
      }
    }
    const G = unorm8Encode(f32((dir[0] + 1) * 0.5)), B = unorm8Encode(f32((dir[1] + 1) * 0.5)), A = unorm8Encode(f32(dir[2]));
    const d = ahdDirection(G, B, A);
    const k = f32(0.25 + f32(0.5 * d[2]));
    const a = [0, 0, 0], ez = [0, 0, 0];
    let lumA = 0, lumEz = 0;
    for (let c = 0; c < 3; c++) {
      const gd = f32(f32(f32(g[c][0] * d[0]) + f32(g[c][1] * d[1])) + f32(g[c][2] * d[2]));
      const inten = gd > 0 ? f32(2 * gd) : 0;
      const amb = f32(e0[c] - f32(0.25 * inten));
      a[c] = amb > 0 ? amb : 0;
      ez[c] = f32(a[c] + f32(inten * k));
      lumA += LUM[c] * a[c];
      lumEz += LUM[c] * ez[c];
    }
    return [r11g11b10fPack(ez), lumEz > 0 ? unorm8Encode(f32(lumA / lumEz)) : 255, G, B, A];
  }
  /* lbk_sh9_pack of 27 floats [ch·9 + k] (stored units) into out[o..o+28) */
  function sh9Pack(sh, out, o) {
    const w = rgb9e5Pack([sh[0], sh[9], sh[18]]);
    const dq = rgb9e5(w);
    out[o] = w & 255; out[o + 1] = (w >>> 8) & 255; out[o + 2] = (w >>> 16) & 255; out[o + 3] = w >>> 24;
    for (let k = 1; k < 9; k++)
      for (let c = 0; c < 3; c++)
        out[o + 4 + 3 * (k - 1) + c] = dq[c] > 0 ? snorm8Encode(f32(sh[9 * c + k] / f32(BAND_SCALE[k] * dq[c]))) : 0;
  }

  /* ---- DLS (§12) and DOOR (§13) ----------------------------------------------------------------- */
  const FORMS = { 2: [2, 5, 16, 16], 3: [3, 9, 10, 8], 4: [8, 17, 4, 16] }; /* b, bias, F, B */
  function parseDls(p) {
    if (!p) return null;
    const dv = view(p); need(p, 96, 'DLS');
    const H = (i) => dv.getUint32(4 * i, true);
    const nSets = H(0), nRefs = H(1), nMembers = H(2), nClusters = H(3), nClusterSets = H(4), nRuns = H(5), nSub = H(6),
          nWords = H(7), nB16 = H(8), nB32 = H(9);
    const nSlots = u64(dv, 40), nTexE = u64(dv, 48), nProbeE = u64(dv, 56), nStr = u64(dv, 64);
    const targets = [u64(dv, 72), u64(dv, 80), u64(dv, 88)];
    const sizes = [32 * nSets, 8 * nRefs, 4 * nMembers, 64 * nClusters, 4 * nClusterSets, 8 * nRuns, 16 * nSub, 4 * nWords,
                   2 * nB16, 4 * nB32, nSlots, 8 * nTexE, 28 * nProbeE, nStr];
    const at = [];
    let pos = 96;
    for (const n of sizes) { pos = align16(pos); at.push(pos); pos += n; }
    if (align16(pos) !== p.length) fail('DLS: size does not match its counts');
    const u32 = (arr, i) => dv.getUint32(at[arr] + 4 * i, true);
    const strings = p.subarray(at[13], at[13] + nStr);
    const sets = [];
    for (let i = 0; i < nSets; i++) {
      const o = at[0] + 32 * i, r = (k) => dv.getUint32(o + 4 * k, true);
      if (r(0) + r(1) > nStr || r(5) + r(6) > nMembers || r(2) > 3) fail('DLS set ' + i + ': out of range');
      const members = [];
      for (let m = 0; m < r(6); m++) members.push(u32(2, r(5) + m));
      sets.push({ name: utf8.decode(strings.subarray(r(0), r(0) + r(1))), kind: r(2), members });
    }
    const clusters = [];
    for (let i = 0; i < nClusters; i++) {
      const o = at[3] + 64 * i, r = (k) => dv.getUint32(o + 4 * k, true);
      const c = { form: r(0), space: r(1), overlaps: r(2), set_first: r(3), set_count: r(4), run_first: r(5), run_count: r(6),
                  target_count: r(7), aux_first: r(8), aux_count: r(9), base_first: r(10), entry_count: r(11),
                  entry_first: u64(dv, o + 48), slot_first: u64(dv, o + 56) };
      if (c.form > 4 || c.space > 2 || c.set_first + c.set_count > nClusterSets || c.run_first + c.run_count > nRuns) fail('DLS cluster ' + i + ': out of range');
      c.sets = [];
      for (let k = 0; k < c.set_count; k++) { const s = u32(4, c.set_first + k); if (s >= nSets) fail('DLS cluster set'); c.sets.push(s); }
      clusters.push(c);
    }
    const runTargets = (first, count, out) => {
      for (let r = first; r < first + count; r++) {
        const st = u32(5, 2 * r), ln = u32(5, 2 * r + 1);
        for (let t = st; t < st + ln; t++) out.push(t);
      }
      return out;
    };
    /* calls fn(target, [[set, entry index], ...]) for every target of cluster c, in cluster order */
    function forEachTarget(c, fn) {
      const targetsOf = runTargets(c.run_first, c.run_count, []);
      if (targetsOf.length !== c.target_count) fail('DLS: run lengths do not add up to target_count');
      const nE = c.space === 0 ? nTexE : nProbeE;
      if (c.entry_first + c.entry_count > nE) fail('DLS: cluster entries outside the entry array');
      if (c.form === 0) {
        const k = c.set_count;
        targetsOf.forEach((t, i) => fn(t, c.sets.map((s, j) => [s, c.entry_first + i * k + j])));
      } else if (c.form === 1) {
        const k = c.overlaps;
        for (let g = c.aux_first; g < c.aux_first + c.aux_count; g++) {
          const o = at[6] + 16 * g, rf = dv.getUint32(o, true), rc = dv.getUint32(o + 4, true), tf = dv.getUint32(o + 8, true);
          const slot = [p[o + 12], p[o + 13], p[o + 14], p[o + 15]];
          runTargets(rf, rc, []).forEach((t, i) =>
            fn(t, slot.slice(0, k).map((sl, j) => [c.sets[sl], c.entry_first + (tf + i) * k + j])));
        }
      } else {
        const [b, bias, F, Bt] = FORMS[c.form];
        let off = 0;
        targetsOf.forEach((t, i) => {
          if (i % Bt === 0) {
            const base = c.form === 4 ? u32(9, c.base_first + i / Bt) : dv.getUint16(at[8] + 2 * (c.base_first + i / Bt), true);
            if (base !== off) fail('DLS: a prefix base is not the running entry count');
          }
          const word = u32(7, c.aux_first + Math.floor(i / F));
          const cnt = ((word >>> (b * (i % F))) & ((1 << b) - 1)) + bias;
          const list = [];
          for (let e = 0; e < cnt; e++) {
            const sl = p[at[10] + c.slot_first + off + e];
            if (sl >= c.set_count) fail('DLS: slot outside the set list');
            list.push([c.sets[sl], c.entry_first + off + e]);
          }
          off += cnt;
          fn(t, list);
        });
      }
    }
    return { sets, clusters, targets, forEachTarget, texel_entries: p.subarray(at[11], at[11] + 8 * nTexE),
             probe_entries: p.subarray(at[12], at[12] + 28 * nProbeE) };
  }
  function parseDoor(p) {
    if (!p) return null;
    const dv = view(p); need(p, 32, 'DOOR');
    const E = dv.getUint32(0, true), S = dv.getUint32(4, true), SD = dv.getUint32(8, true), nStr = u64(dv, 16);
    const strAt = align16(align16(align16(32 + 80 * E) + 16 * S) + 4 * SD);
    need(p, strAt + nStr, 'DOOR strings');
    const doors = [];
    for (let i = 0; i < E; i++) {
      const o = 32 + 80 * i, no = dv.getUint32(o, true), nl = dv.getUint32(o + 4, true);
      if (no + nl > nStr) fail('DOOR: name outside the blob');
      doors.push({ name: utf8.decode(p.subarray(strAt + no, strAt + no + nl)), open_set: dv.getUint32(o + 68, true),
                   closed_set: dv.getUint32(o + 72, true) });
    }
    return doors;
  }
  /* lbk_dls_effective_weights: per set, from the caller's set weights and door openings */
  function effectiveWeights(dls, doors, setWeights, doorWeights) {
    const n = dls.sets.length, w = new Float32Array(n), doorOf = new Array(n).fill(-1);
    (doors || []).forEach((d, i) => { doorOf[d.open_set] = i; if (d.closed_set !== 0xffffffff) doorOf[d.closed_set] = i; });
    for (let s = 0; s < n; s++) {
      let x = setWeights ? f32(setWeights[s] || 0) : 0;
      if (doorOf[s] >= 0) {
        const om = doorWeights ? f32(doorWeights[doorOf[s]] || 0) : 0;
        x = dls.sets[s].kind === 1 ? om : f32(1 - om);
      }
      w[s] = x;
    }
    for (let s = 0; s < n; s++) {
      if (dls.sets[s].kind !== 3) continue;
      let x = 1;
      for (const m of dls.sets[s].members) x = f32(x * w[m]);
      w[s] = x;
    }
    return w;
  }
  /* §12.8 for the given weights, from the base: returns {z, rgba, glg, llg} (new arrays; stored
   * units) — the bytes lbk_dls_apply writes. base: {z: Uint32Array, rgba: Uint8Array, glg, llg:
   * Uint8Array of packed SH9}, any may be null when its space has no cluster. */
  function dlsApply(dls, doors, base, setWeights, doorWeights) {
    const w = effectiveWeights(dls, doors, setWeights, doorWeights);
    const out = { z: base.z && base.z.slice(), rgba: base.rgba && base.rgba.slice(), glg: base.glg && base.glg.slice(),
                  llg: base.llg && base.llg.slice() };
    const te = view(dls.texel_entries), lin = new Float32Array(12), el = new Float32Array(12);
    for (const c of dls.clusters) {
      if (!c.sets.some((s) => w[s] !== 0)) continue; /* all weights 0: the base, as copied */
      dls.forEachTarget(c, (t, list) => {
        const on = list.filter(([s]) => w[s] !== 0);
        if (!on.length) return;
        if (c.space === 0) {
          ahdToLinear(base.z[t], base.rgba.subarray(4 * t, 4 * t + 4), lin, 0);
          for (const [s, e] of on) {
            ahdToLinear(te.getUint32(8 * e, true), dls.texel_entries.subarray(8 * e + 4, 8 * e + 8), el, 0);
            for (let k = 0; k < 12; k++) lin[k] = f32(lin[k] + f32(w[s] * el[k]));
          }
          const r = ahdFromLinear(lin, 0);
          out.z[t] = r[0];
          out.rgba.set(r.slice(1), 4 * t);
        } else {
          const b = c.space === 1 ? base.glg : base.llg, o = c.space === 1 ? out.glg : out.llg;
          const acc = sh9Unpack(b, 28 * t, 1);
          for (const [s, e] of on) {
            const sh = sh9Unpack(dls.probe_entries, 28 * e, 1);
            for (let k = 0; k < 27; k++) acc[k] = f32(acc[k] + f32(w[s] * sh[k]));
          }
          sh9Pack(acc, o, 28 * t);
        }
      });
    }
    return out;
  }

  return { open, LbkError, errorOfCode, pageLinear, pageTexelsF, texelFToLinear, bc6hUnpack, bc4Unpack, parseDls, parseDoor, dlsApply, effectiveWeights, ahdFromLinear, sh9Pack, r11g11b10fPack, rgb9e5Pack, linearEval, sh9Unpack, r11g11b10f, rgb9e5, half, unorm8, snorm8, ahdToLinear };
}));
