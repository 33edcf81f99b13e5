"""A small OpenEXR reader (plain Python 3, no packages): single-part scanline files with
NONE, ZIPS or ZIP compression and HALF or FLOAT channels: what `lbk render` (ZIP, FLOAT) and
Blender (set up by cycles_render.py: ZIP, FLOAT) write. Layout: OpenEXR "File Layout" spec."""
import array
import struct
import zlib

_LINES = {0: 1, 2: 1, 3: 16}  # compression -> scanlines per block: NONE, ZIPS, ZIP


def _attributes(data):
    if data[:4] != b"\x76\x2f\x31\x01":
        raise ValueError("not an OpenEXR file")
    if struct.unpack_from("<I", data, 4)[0] & 0x1600:  # tiled, long names ok, deep, multipart
        if struct.unpack_from("<I", data, 4)[0] & 0x1200:
            raise ValueError("tiled, deep or multi-part EXR")
    off, attrs = 8, {}
    while data[off] != 0:
        end = data.index(b"\0", off)
        name = data[off:end].decode()
        end2 = data.index(b"\0", end + 1)
        kind = data[end + 1:end2].decode()
        size = struct.unpack_from("<i", data, end2 + 1)[0]
        attrs[name] = (kind, data[end2 + 5:end2 + 5 + size])
        off = end2 + 5 + size
    return attrs, off + 1


def _channels(blob):
    out, off = [], 0
    while blob[off] != 0:
        end = blob.index(b"\0", off)
        name = blob[off:end].decode()
        ptype = struct.unpack_from("<i", blob, end + 1)[0]
        out.append((name, ptype))
        off = end + 1 + 16
    return out


def _unzip(raw, size):
    t = bytearray(zlib.decompress(raw))
    for i in range(1, len(t)):  # undo the predictor
        t[i] = (t[i - 1] + t[i] - 128) & 0xFF
    half = (len(t) + 1) // 2  # undo the interleave of even and odd bytes
    out = bytearray(len(t))
    out[0::2] = t[:half]
    out[1::2] = t[half:]
    if len(out) != size:
        raise ValueError("EXR block decodes to %d bytes, not %d" % (len(out), size))
    return bytes(out)


def read(path, names=("R", "G", "B")):
    """(width, height, {name: array('f') row-major, row 0 at the top}) for the named channels."""
    data = open(path, "rb").read()
    attrs, off = _attributes(data)
    comp = attrs["compression"][1][0]
    if comp not in _LINES:
        raise ValueError("%s: EXR compression %d is not supported" % (path, comp))
    x0, y0, x1, y1 = struct.unpack("<4i", attrs["dataWindow"][1])
    w, h = x1 - x0 + 1, y1 - y0 + 1
    chans = _channels(attrs["channels"][1])  # sorted by name, as EXR stores them
    sizes = [2 if t == 1 else 4 for _, t in chans]
    lines = _LINES[comp]
    nblocks = (h + lines - 1) // lines
    offsets = struct.unpack_from("<%dQ" % nblocks, data, off)
    planes = {n: array.array("f", [0.0]) * (w * h) for n, _ in chans}
    for b in range(nblocks):
        y, size = struct.unpack_from("<ii", data, offsets[b])
        raw = data[offsets[b] + 8: offsets[b] + 8 + size]
        nl = min(lines, y1 + 1 - y)
        expect = nl * w * sum(sizes)
        block = raw if size == expect else _unzip(raw, expect)
        p = 0
        for j in range(nl):
            row = y - y0 + j
            for (n, t), s in zip(chans, sizes):
                fmt = "<%d%s" % (w, "e" if t == 1 else ("f" if t == 2 else "I"))
                vals = struct.unpack_from(fmt, block, p)
                planes[n][row * w: row * w + w] = array.array("f", vals)
                p += s * w
    missing = [n for n in names if n not in planes]
    if missing:
        raise ValueError("%s: no channel %s (it has %s)" % (path, missing, [n for n, _ in chans]))
    return w, h, {n: planes[n] for n in names}
