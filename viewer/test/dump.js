#!/usr/bin/env node
/* node viewer/test/dump.js FILE.lbk OUT.txt
 * Writes what viewer/lbk_reader.js decodes from FILE.lbk as text lines, floats as the hex of their
 * binary32 bits: tests/tools/test_view_reader.c writes the same lines from liblbk and compares
 * them byte for byte. Exit 1 with the reader's message when it rejects the file. */
'use strict';
const fs = require('fs');
const path = require('path');
const vendor = path.join(__dirname, '..', 'vendor');
const fzstd = require(path.join(vendor, 'fzstd.js'));
const { xxhash3 } = require(path.join(vendor, 'xxhash3.js'));
const R = require(path.join(__dirname, '..', 'lbk_reader.js'));

const fb = new DataView(new ArrayBuffer(8));
function fx(x) { fb.setFloat32(0, x, true); return fb.getUint32(0, true).toString(16).padStart(8, '0'); }
function dx(x) { fb.setFloat64(0, x, true); return fb.getUint32(4, true).toString(16).padStart(8, '0') + fb.getUint32(0, true).toString(16).padStart(8, '0'); }
const hex = (s) => Buffer.from(s, 'utf8').toString('hex');
const fl = (arr) => Array.from(arr, fx).join(' ');

/* --apply W0,W1,... D0,...: the DLS outputs (§12.8) for those set weights and door openings, as the
 * hex of the stored bytes per space (texel words little-endian, RGBA, GLG, LLG probes) */
async function dumpApply(lbk, lm, glg, llg, setArg, doorArg, out) {
  const dls = await lbk.dls(), doors = await lbk.doors();
  const nums = (s) => (s ? s.split(',').filter((x) => x !== '').map(Number) : []);
  const base = { z: null, rgba: null, glg: null, llg: null };
  if (lm) {
    base.z = new Uint32Array(lm.texel_count); base.rgba = new Uint8Array(4 * lm.texel_count);
    for (const pg of lm.pages) {
      base.z.set(new Uint32Array(pg.plane0.buffer.slice(pg.plane0.byteOffset, pg.plane0.byteOffset + pg.plane0.length)), pg.first_texel);
      base.rgba.set(pg.plane1, 4 * pg.first_texel);
    }
  }
  const p = await lbk.payload('GLG '), q = await lbk.payload('LLG ');
  if (glg) { const o = 32 + Math.ceil(12 * glg.probe_count / 16) * 16; base.glg = p.slice(o, o + 28 * glg.probe_count); }
  if (llg) { const o = Math.ceil((32 + 96 * llg.grids.length) / 16) * 16, n = llg.grids.reduce((a, g) => a + g.sh.length / 27, 0); base.llg = q.slice(o, o + 28 * n); }
  const r = R.dlsApply(dls, doors, base, nums(setArg), nums(doorArg));
  const h = (u8) => Buffer.from(u8.buffer, u8.byteOffset, u8.byteLength).toString('hex');
  out.push('W ' + fl(R.effectiveWeights(dls, doors, nums(setArg), nums(doorArg))));
  if (r.z) out.push('AZ ' + h(r.z)), out.push('AR ' + h(r.rgba));
  if (r.glg) out.push('AG ' + h(r.glg));
  if (r.llg) out.push('AL ' + h(r.llg));
}

async function main() {
  const [file, outPath, applyFlag, setArg, doorArg] = process.argv.slice(2);
  if (!file || !outPath) { console.error('usage: dump.js FILE.lbk OUT.txt'); process.exit(2); }
  const deps = { decompress: (u8) => fzstd.decompress(u8), xxh3: (u8) => xxhash3(u8) };
  const lbk = await R.open(fs.readFileSync(file), deps);
  for (const s of lbk.sections) await lbk.payload(s.type); /* every checksum, zstd frame */
  const out = [];
  out.push('FILE ' + lbk.version.join('.') + ' ' + lbk.sections.map((s) => s.type.trim()).join(','));
  const meta = await lbk.meta();
  if (meta) for (const k of Object.keys(meta)) out.push('META ' + hex(k) + ' ' + hex(meta[k]));
  const rep = await lbk.report();
  if (rep) {
    out.push('REPT ' + rep.status + ' ' + rep.records.length + ' ' + rep.max_samples_per_texel + ' ' + dx(rep.time_limit_seconds) + ' ' + fx(rep.target_rel_rmse));
    for (const r of rep.records)
      out.push('R ' + dx(r.elapsed_seconds) + ' ' + r.rays_traced + ' ' + r.samples_per_texel + ' ' + r.bounces + ' ' + fx(r.texel_rel_rmse) + ' ' + fx(r.probe_rel_rmse));
  }
  const objs = await lbk.objects();
  if (objs) objs.forEach((o, i) => out.push('OBJ ' + i + ' ' + hex(o.name) + ' ' + o.geometry_hash + ' ' + o.representation + ' ' + o.index + ' ' + o.rect.join(' ')));
  const lm = await lbk.lightmap();
  if (lm) {
    out.push('LMAP ' + fx(lm.scale) + ' ' + lm.pages.length + ' ' + lm.texel_count);
    lm.pages.forEach((pg, i) => {
      out.push('PAGE ' + i + ' ' + pg.width + ' ' + pg.height + ' ' + pg.format0 + ' ' + pg.format1 + ' ' + pg.first_texel);
      if (pg.format0 === 2 || pg.format1 === 2) { out.push('ASTC'); return; } /* no ASTC decoder in JS */
      const lin = R.pageLinear(lm, i);
      for (let t = 0; t < pg.width * pg.height; t++) out.push('T ' + fl(lin.subarray(12 * t, 12 * t + 12)));
    });
  }
  const em = await lbk.errorMap();
  if (em) {
    out.push('TERR ' + em.texel_count + ' ' + (em.denoised ? 1 : 0));
    for (let o = 0; o < em.texel_count; o += 4096) out.push('E ' + Buffer.from(em.codes.subarray(o, o + 4096)).toString('hex'));
  }
  const glg = await lbk.glg();
  if (glg) {
    out.push('GLG ' + glg.probe_count + ' ' + glg.tetra_count + ' ' + fx(glg.scale));
    for (let i = 0; i < glg.probe_count; i++)
      out.push('G ' + fl(glg.positions.subarray(3 * i, 3 * i + 3)) + ' ' + fl(glg.sh.subarray(27 * i, 27 * i + 27)));
    for (let t = 0; t < glg.tetra_count; t++)
      out.push('GT ' + Array.from(glg.tetras.subarray(4 * t, 4 * t + 4)).join(' ') + ' ' + Array.from(glg.visibility.subarray(4 * t, 4 * t + 4)).join(' '));
  }
  const llg = await lbk.llg();
  if (llg) {
    out.push('LLG ' + llg.grids.length + ' ' + fx(llg.scale));
    llg.grids.forEach((g, i) => {
      out.push('GRID ' + i + ' ' + fl(g.centre) + ' ' + fl(g.axes.flat()) + ' ' + fl(g.half_extents) + ' ' + g.n.join(' ') + ' ' + g.vertex_count);
      for (let p = 0; p < g.sh.length / 27; p++) out.push('L ' + fl(g.sh.subarray(27 * p, 27 * p + 27)));
      out.push('V ' + Buffer.from(g.vertices).toString('hex'));
    });
  }
  const oct = await lbk.octp();
  if (oct) {
    out.push('OCTP ' + oct.probes.length + ' ' + fx(oct.scale));
    for (const l of oct.levels)
      out.push('OL ' + fl(l.origin) + ' ' + fx(l.spacing) + ' ' + l.dims.join(' ') + ' ' + l.first_probe + ' ' + fx(l.miss_distance));
    for (const p of oct.probes) {
      out.push('O ' + fl(p.position) + ' ' + fl(p.irradiance) + ' ' + fl(p.depth));
      if (p.state !== undefined) out.push('OI ' + fl(p.offset) + ' ' + p.state + ' ' + p.rays + ' ' + fx(p.backface) + ' ' + fx(p.nearest));
    }
  }
  if (applyFlag === '--apply') await dumpApply(lbk, lm, glg, llg, setArg, doorArg, out);
  fs.writeFileSync(outPath, out.join('\n') + '\n');
}
main().catch((e) => { console.error('lbk reader: ' + e.message); process.exit(1); });
