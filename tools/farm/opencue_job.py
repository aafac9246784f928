#!/usr/bin/env python3
"""Submits a tiled (and/or multi-frame) vdbmarch render to OpenCue with PyOutline.

A template, not run here (no Cuebot in this project's CI): docs/farm.md.

    python3 tools/farm/opencue_job.py [OPTIONS] SCENE -o OUT.exr [-- RENDER_OPTIONS...]

The outline (one OpenCue job) has:
  * tiles only (--tiles N):  layer "render" over frames 0..N-1, the OpenCue frame
    number being the tile index: `vdbmarch render SCENE --tile #IFRAME#/N -o
    WORKDIR/NAME.tile_#IFRAME#ofN.exr`; layer "merge" (one frame, Util) that
    depend_all()s on it and runs `vdbmarch merge` into OUT.
  * frames only (--frames A-B[:STEP], --tiles 1): layer "render" over the frames,
    `--frames #IFRAME#-#IFRAME#`, writing OUT with its #### replaced; no merge.
  * frames and tiles: one layer "render_tI" per tile over the frames, and layer
    "merge" over the frames that depend_on()s (frame by frame) every tile
    layer, so frame F is merged as soon as its N tiles are done.
Commands are shell strings (launched with use_pycuerun=False: RQD runs them with
/bin/sh after Cuebot replaces #IFRAME#/#ZFRAME#), so paths are shell-quoted.
--dry-run prints every command it would schedule, tokens expanded, without
importing outline: the output is a runnable shell script. --print-spec builds the
outline and prints the job spec XML that launch would send to Cuebot.
"""

import argparse
import getpass
import os
import re
import shlex
import sys


def parse_frames(spec):
    m = re.fullmatch(r"(\d+)(?:-(\d+))?(?::(\d+))?", spec)
    if not m:
        raise argparse.ArgumentTypeError("--frames wants A-B[:STEP], e.g. 1-24 or 1-24:2, not %r" % spec)
    first = int(m.group(1))
    last = int(m.group(2) or first)
    step = int(m.group(3) or 1)
    if last < first or step < 1:
        raise argparse.ArgumentTypeError("--frames %s: need A <= B and STEP >= 1" % spec)
    return first, last, step


def positive(value):
    if not re.fullmatch(r"\d+", value) or int(value) < 1:
        raise argparse.ArgumentTypeError("wants a positive integer, not %r" % value)
    return int(value)


def parse_args(argv):
    extra = []
    if "--" in argv:
        cut = argv.index("--")
        argv, extra = argv[:cut], argv[cut + 1:]
    p = argparse.ArgumentParser(
        prog="opencue_job.py",
        description="Submit a tiled/multi-frame vdbmarch render to OpenCue (PyOutline). "
                    "Render options go after --.")
    p.add_argument("scene", help="scene .json or .vdb, as seen from the render nodes")
    p.add_argument("-o", "--output", required=True,
                   help="merged image OUT.exr; with --frames it contains #### (the frame number)")
    p.add_argument("--tiles", type=positive, default=1, help="tiles per frame (render --tile I/N)")
    p.add_argument("--frames", type=parse_frames, help="A-B[:STEP]")
    p.add_argument("--workdir", help="where tiles go (default OUTDIR/NAME.farm); shared by all hosts")
    p.add_argument("--vdbmarch", default="vdbmarch", help="the binary on the render nodes (default: on PATH)")
    p.add_argument("--name", help="job name part (default: NAME, from the output file name)")
    p.add_argument("--show", default=os.environ.get("SHOW", "testing"))
    p.add_argument("--shot", default=os.environ.get("SHOT", "vdbmarch"))
    p.add_argument("--user", default=os.environ.get("USER") or getpass.getuser())
    p.add_argument("--service", help="OpenCue service of the render layers (default: the site's)")
    p.add_argument("--cores", type=float, help="cores per render frame (default: the service's)")
    p.add_argument("--memory", help="memory per render frame, e.g. 4g (default: the service's)")
    p.add_argument("--tags", help="host tags of the render layers, e.g. 'general | farm'")
    p.add_argument("--pause", action="store_true", help="launch the job paused")
    p.add_argument("--print-spec", action="store_true",
                   help="build the outline and print the OpenCue job spec (XML) instead of launching")
    p.add_argument("--dry-run", action="store_true",
                   help="print the commands it would schedule (a shell script); import nothing, submit nothing")
    a = p.parse_args(argv)
    a.extra = extra
    for opt in ("-o", "--output", "--tile", "--crop", "--frames"):
        if any(x == opt or x.startswith(opt + "=") for x in extra):
            p.error("RENDER_OPTIONS must not set %s: this script sets it" % opt)
    if not a.output.endswith(".exr"):
        p.error("the output must be an .exr file, not %r" % a.output)
    token = re.search(r"#+", os.path.basename(a.output))
    if a.frames and not token:
        p.error("with --frames the output needs a frame token, e.g. %s.####.exr" % a.output[:-4])
    if not a.frames and token:
        p.error("the output %r has a frame token but no --frames was given" % a.output)
    a.pad = len(token.group(0)) if token else 0
    return a


class Plan:
    """The layers to schedule, independent of PyOutline (shared by --dry-run and launch)."""

    def __init__(self, a):
        self.a = a
        out = os.path.abspath(a.output)
        base = os.path.basename(out)[:-len(".exr")]
        name = re.sub(r"[._]?#+", "", base) or "render"
        name = re.sub(r"[^A-Za-z0-9._+-]", "_", name)
        self.name = a.name or name
        self.out = out
        self.workdir = os.path.abspath(a.workdir or os.path.join(os.path.dirname(out), name + ".farm"))
        self.tile_prefix = os.path.join(self.workdir, name + ".tile_")
        self.scene = os.path.abspath(a.scene)
        self.vdbmarch = a.vdbmarch if "/" not in a.vdbmarch else os.path.abspath(a.vdbmarch)
        threads = [] if any(x == "--threads" or x.startswith("--threads=") for x in a.extra) \
            else ['--threads "${CUE_THREADS:-1}"']  # the cores OpenCue booked
        self.extra = threads + [shlex.quote(x) for x in a.extra]
        if a.frames:
            first, last, step = a.frames
            self.frame_range = "%d-%d" % (first, last) + ("x%d" % step if step > 1 else "")
            self.frames = list(range(first, last + 1, step))
        else:
            self.frame_range, self.frames = None, []

    def frame_word(self, path):
        """PATH with its run of '#' replaced by the OpenCue frame, as one shell word."""
        m = re.search(r"#+", path)
        if not m:
            return shlex.quote(path)
        if len(m.group(0)) == 4:
            frame = "#ZFRAME#"  # Cuebot's 4-digit zero-padded frame number
        else:
            frame = '"$(printf %%0%dd #IFRAME#)"' % len(m.group(0))
        return shlex.quote(path[:m.start()]) + frame + shlex.quote(path[m.end():])

    def tile_word(self, tile, framed):
        return self.frame_word("%s%sof%d%s.exr" % (self.tile_prefix, tile, self.a.tiles,
                                                  ".####" if framed else ""))

    def render_cmd(self, tile_arg, out_word, framed):
        words = [shlex.quote(self.vdbmarch), "render", shlex.quote(self.scene)]
        if framed:
            words += ["--frames", "#IFRAME#-#IFRAME#"]
        if tile_arg:
            words += ["--tile", tile_arg]
        return " ".join(words + ["-o", out_word, "-q"] + self.extra)

    def merge_cmd(self, framed):
        tiles = [self.tile_word(i, framed) for i in range(self.a.tiles)]
        out = self.frame_word(self.out) if framed else shlex.quote(self.out)
        return " ".join([shlex.quote(self.vdbmarch), "merge"] + tiles + ["-o", out])

    def layers(self):
        """[(name, type, range, command, [(depend_kind, layer name)])]"""
        a, n = self.a, self.a.tiles
        mkdir_out = "mkdir -p %s && " % shlex.quote(os.path.dirname(self.out))
        mkdir = "mkdir -p %s %s && " % (shlex.quote(self.workdir), shlex.quote(os.path.dirname(self.out)))
        if not self.frames:  # one image
            if n == 1:
                return [("render", "Render", "0", mkdir_out + self.render_cmd(None, shlex.quote(self.out), False), [])]
            # tiles of one image: the OpenCue frame number is the tile index
            tile_out = shlex.quote(self.tile_prefix) + "#IFRAME#" + shlex.quote("of%d.exr" % n)
            render = ("render", "Render", "0-%d" % (n - 1),
                      mkdir + self.render_cmd("#IFRAME#/%d" % n, tile_out, False), [])
            merge = ("merge", "Util", "0", self.merge_cmd(False), [("all", "render")])
            return [render, merge]
        if n == 1:  # frames only
            return [("render", "Render", self.frame_range,
                     mkdir_out + self.render_cmd(None, self.frame_word(self.out), True), [])]
        layers = [("render_t%d" % i, "Render", self.frame_range,
                   mkdir + self.render_cmd("%d/%d" % (i, n), self.tile_word(i, True), True), [])
                  for i in range(n)]
        merge = ("merge", "Util", self.frame_range, self.merge_cmd(True),
                 [("frame", "render_t%d" % i) for i in range(n)])
        return layers + [merge]


def expand(cmd, frame):
    return cmd.replace("#ZFRAME#", "%04d" % frame).replace("#IFRAME#", str(frame))


def range_frames(spec, plan):
    if spec == "0":
        return [0]
    if plan.frames and spec == plan.frame_range:
        return plan.frames
    lo, hi = spec.split("-")
    return list(range(int(lo), int(hi) + 1))


def dry_run(plan):
    print("#!/bin/sh")
    print("# vdbmarch OpenCue job %s-%s-%s_%s (dry run: the frames OpenCue would run, in a valid order)"
          % (plan.a.show, plan.a.shot, plan.a.user, plan.name))
    print("set -e")
    for name, ltype, rng, cmd, deps in plan.layers():
        dep = ", ".join("%s %s" % ("depend_all on" if k == "all" else "frame-by-frame on", d) for k, d in deps)
        print("# layer %s (%s), range %s%s" % (name, ltype, rng, "; " + dep if dep else ""))
        print("#   command: %s" % cmd)
        for f in range_frames(rng, plan):
            print(expand(cmd, f))


def launch(plan):
    # Imported here so that --dry-run and py_compile need no OpenCue install.
    # pylint: disable=import-outside-toplevel
    try:
        import outline
        import outline.cuerun
        import outline.modules.shell
    except ImportError as e:
        sys.exit("opencue_job.py: PyOutline is not importable (%s): install OpenCue's pyoutline and "
                 "pycue (with their configuration: OUTLINE_CONFIG_FILE, OPENCUE_CONFIG_FILE), or use "
                 "--dry-run" % e)

    a = plan.a
    ol = outline.Outline(plan.name, shot=a.shot, show=a.show, user=a.user)
    by_name = {}
    for name, ltype, rng, cmd, deps in plan.layers():
        args = {"command": cmd, "range": rng, "type": ltype}
        if ltype == "Render":
            for key in ("service", "cores", "memory", "tags"):
                if getattr(a, key) is not None:
                    args[key] = getattr(a, key)
        layer = outline.modules.shell.Shell(name, **args)
        for kind, on in deps:
            if kind == "all":
                layer.depend_all(by_name[on])
            else:
                layer.depend_on(by_name[on])  # FrameByFrame: frame F waits for frame F of `on`
        ol.add_layer(layer)
        by_name[name] = layer
    if a.print_spec:
        launcher = outline.cuerun.OutlineLauncher(ol, pause=a.pause, nomail=True)
        print(launcher.serialize(use_pycuerun=False))
        return 0
    jobs = outline.cuerun.launch(ol, use_pycuerun=False, pause=a.pause, nomail=True)
    for job in jobs or []:
        print("launched %s" % (job.name() if hasattr(job, "name") else job))
    return 0


def main(argv):
    a = parse_args(argv)
    plan = Plan(a)
    if a.dry_run:
        dry_run(plan)
        return 0
    return launch(plan)


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
