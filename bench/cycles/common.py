"""Shared helpers of the Cycles comparison (plain Python 3, no packages)."""
import array
import json
import os
import resource
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
LUM = (0.2126, 0.7152, 0.0722)  # Rec. 709, as lbk (lbk/ahd.h)
HIDDEN = 0x100  # texel_dump: the sensor point is enclosed by geometry (no reference value)
OFFPLANE = 0x200  # texel_dump: push-out moved the point off its own (covered) surface


def lum(rgb):
    return LUM[0] * rgb[0] + LUM[1] * rgb[1] + LUM[2] * rgb[2]


class Receivers:
    """texel_dump's TSV: header keys, objects, materials and one row per receiver. Footprint rows
    (P, texel_dump --footprint K) are not receivers: every row is a Cycles sensor, in file order,
    and footprint[i] lists the sensors of receiver i's footprint points (empty: its own point)."""

    def __init__(self, path):
        self.meta, self.objects, self.materials = {}, {}, {}
        self.kind, self.obj, self.mat, self.pos, self.nrm, self.size, self.rgb = [], [], [], [], [], [], []
        self.flags = []
        self.sensor, self.footprint = [], []  # per receiver: its own sensor, its footprint's sensors
        self.sensors = 0
        with open(path) as f:
            for line in f:
                if line.startswith("#"):
                    w = line[1:].strip().split(" ", 1)
                    if w[0] == "object":
                        i, rep, name = w[1].split(" ", 2)
                        self.objects[int(i)] = (rep, name)
                    elif w[0] == "material":
                        i, name = w[1].split(" ", 1)
                        self.materials[int(i)] = name
                    elif len(w) == 2:
                        self.meta[w[0]] = w[1]
                    continue
                c = line.rstrip("\n").split("\t")
                if len(c) < 16:
                    continue
                self.sensors += 1
                if c[0] == "P":  # a footprint point of the receiver whose T row came last
                    # an enclosed point (HIDDEN: inside a sill let into the wall, under a crate)
                    # is no part of the texel's visible surface: its sensor is read but not averaged
                    if not (len(c) > 16 and int(c[16]) & HIDDEN):
                        self.footprint[-1].append(self.sensors - 1)
                    continue
                self.sensor.append(self.sensors - 1)
                self.footprint.append([])
                self.kind.append(c[0])
                self.obj.append(int(c[1]))
                self.mat.append(int(c[2]))
                self.pos.append((float(c[6]), float(c[7]), float(c[8])))
                self.nrm.append((float(c[9]), float(c[10]), float(c[11])))
                self.size.append(float(c[12]))
                self.rgb.append((float(c[13]), float(c[14]), float(c[15])))
                self.flags.append(int(c[16]) if len(c) > 16 else 0)

    def __len__(self):
        return len(self.pos)

    def per_receiver(self, values):
        """Sensor values (one per row of the file) -> one per receiver: the mean over its visible
        footprint points where it has them (the average over the visible part of the texel's
        square, what a texel should hold), else its own."""
        if len(values) != self.sensors:
            raise SystemExit("bench-cycles: %d sensor values for %d sensors" % (len(values), self.sensors))
        out = []
        for own, fp in zip(self.sensor, self.footprint):
            out.append(sum(values[k] for k in fp) / len(fp) if fp else values[own])
        return out


def write_point_sensors(src, dst):
    """texel_dump's TSV without its footprint rows (P): one sensor per receiver, at its point."""
    with open(src) as f, open(dst, "w") as g:
        for line in f:
            if not line.startswith("P\t"):
                g.write(line)


def write_receivers(path, pos, nrm, rgb, kind="A", header=None):
    with open(path, "w") as f:
        for k, v in (header or {}).items():
            f.write("# %s %s\n" % (k, v))
        for i, (p, n, e) in enumerate(zip(pos, nrm, rgb)):
            f.write("%s\t0\t0\t0\t%d\t0\t%.9g\t%.9g\t%.9g\t%.7g\t%.7g\t%.7g\t0\t%.7g\t%.7g\t%.7g\n"
                    % (kind, i, p[0], p[1], p[2], n[0], n[1], n[2], e[0], e[1], e[2]))


def read_f32_rgb(path):
    a = array.array("f")
    with open(path, "rb") as f:
        a.frombytes(f.read())
    return [(a[3 * i], a[3 * i + 1], a[3 * i + 2]) for i in range(len(a) // 3)]


def blender():
    return os.environ.get("BLENDER", "blender")


def _file_hash(path):
    import hashlib
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for chunk in iter(lambda: f.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()


def _sensor_hash(path):
    """What Cycles reads of a sensor file (cycles_bake.read_sensors): the points and normals and
    the offset, not lbk's values in the same rows (a new lbk build keeps the reference)."""
    import hashlib
    h = hashlib.sha256()
    with open(path) as f:
        for line in f:
            if line.startswith("# sensor_offset"):
                h.update(line.encode())
            elif not line.startswith("#"):
                h.update("\t".join(line.rstrip("\n").split("\t")[:12]).encode() + b"\n")
    return h.hexdigest()


def run_cycles(scene, sensors, out, runs, sky=(0, 0, 0), threads=0, log=None, equal_time=0.0, clock="cpu",
               refs=(), keep=False):
    """Bakes the sensors in one Blender session: each (spp, seed) of runs, then (equal_time > 0)
    one run at the sample count that takes equal_time on `clock`, then the refs. Returns the
    runs.json entries of this session, in order. keep: when `out` holds a finished session of
    the same inputs (key.json: scene and sensor file hashes, runs, sky, threads, the harness's
    own scripts), return it instead of baking again (BENCH_CYCLES_KEEP_REFS, for references)."""
    key = {"scene": _file_hash(scene) if scene else "", "sensors": _sensor_hash(sensors), "runs": list(map(list, runs)),
           "refs": list(map(list, refs)), "sky": list(sky), "threads": threads, "equal_time": equal_time,
           "harness": [_file_hash(os.path.join(HERE, f)) for f in ("cycles_bake.py", "gltf_scene.py")]}
    key_path = os.path.join(out, "key.json")
    if keep and os.path.exists(key_path) and os.path.exists(os.path.join(out, "runs.json")):
        with open(key_path) as f:
            if json.load(f) == key:
                return json.load(open(os.path.join(out, "runs.json")))
    if os.path.exists(key_path):
        os.remove(key_path)
    cmd = [blender(), "-b", "--factory-startup", "--python", os.path.join(HERE, "cycles_bake.py"), "--",
           "--sensors", sensors, "--out", out, "--sky", ",".join("%g" % x for x in sky),
           "--threads", str(threads), "--runs", ",".join("%d:%d" % r for r in runs),
           "--equal-time", "%.6f" % equal_time, "--clock", clock, "--refs", ",".join("%d:%d" % r for r in refs)]
    if scene:
        cmd += ["--scene", scene]
    if os.path.exists(os.path.join(out, "runs.json")):
        os.remove(os.path.join(out, "runs.json"))
    os.makedirs(out, exist_ok=True)
    with open(log or os.path.join(out, "blender.log"), "a") as lf:
        p = subprocess.run(cmd, stdout=lf, stderr=subprocess.STDOUT)
    if p.returncode != 0:
        sys.exit("bench-cycles: Blender failed (%d); see %s" % (p.returncode, log or os.path.join(out, "blender.log")))
    with open(key_path, "w") as f:
        json.dump(key, f)
    return json.load(open(os.path.join(out, "runs.json")))


def run_timed(cmd, log, who="bench-cycles"):
    """Runs a command; returns (wall s, CPU s of the child = user + system); exits naming `who`
    and the log when it fails."""
    r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    with open(log, "w") as lf:
        p = subprocess.run(cmd, stdout=lf, stderr=subprocess.STDOUT)
    wall = time.perf_counter() - t0
    r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    if p.returncode != 0:
        sys.exit("%s: %s failed (%d); see %s" % (who, cmd[0], p.returncode, log))
    return wall, (r1.ru_utime - r0.ru_utime) + (r1.ru_stime - r0.ru_stime)
