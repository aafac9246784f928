"""Opens a .vdb (a vdbmarch radiance cache) in Blender as a volume object and
lists its grids: shows that Blender's own OpenVDB reader accepts the file.

    blender -b --factory-startup --python tools/blender_open_cache.py -- cache.vdb [--expect NAME ...]

Prints one line per grid: "grid <name> <data_type> channels=<n> loaded=<bool>",
then "blender_open_cache: ok, <n> grids". Exits 1 when the file does not
load, has no grid, a grid does not load, or an --expect name is absent.
"""
import sys

import bpy


def fail(message):
    print("blender_open_cache: error: " + message)
    sys.stdout.flush()
    sys.exit(1)


def main():
    # Blender passes its own arguments through; ours follow "--".
    args = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    if not args:
        fail("usage: blender -b --python blender_open_cache.py -- FILE.vdb [--expect NAME ...]")
    path, expected = args[0], []
    rest = args[1:]
    while rest:
        if rest[0] != "--expect" or len(rest) < 2:
            fail("unknown argument " + rest[0])
        expected.append(rest[1])
        rest = rest[2:]

    # The import operator is what File > Import > OpenVDB runs: it makes the
    # volume datablock and the object that shows it.
    before = set(bpy.data.objects)
    result = bpy.ops.object.volume_import(filepath=path, files=[], align="WORLD", location=(0, 0, 0))
    if "FINISHED" not in result:
        fail("%s: volume_import returned %s" % (path, result))
    added = [o for o in bpy.data.objects if o not in before and o.type == "VOLUME"]
    if not added:
        fail("%s: no volume object was created" % path)
    volume = added[0].data

    # grids.load() reads the file's grid list (metadata only); each grid's
    # load() reads its voxels, which is where a bad file would fail.
    if not volume.grids.load():
        fail("%s: %s" % (path, volume.grids.error_message or "cannot load the grids"))
    print("object %s, volume file %s, %d grids" % (added[0].name, bpy.path.abspath(volume.filepath),
                                                   len(volume.grids)))
    if len(volume.grids) == 0:
        fail("%s: the file has no grids" % path)
    names = set()
    for grid in volume.grids:
        loaded = grid.load()
        print("grid %s %s channels=%d loaded=%s" % (grid.name, grid.data_type, grid.channels, loaded))
        if not loaded:
            fail("%s: grid %s does not load: %s" % (path, grid.name, volume.grids.error_message))
        names.add(grid.name)
    missing = [n for n in expected if n not in names]
    if missing:
        fail("%s: no grid named %s" % (path, ", ".join(missing)))
    print("blender_open_cache: ok, %d grids" % len(volume.grids))
    sys.stdout.flush()


try:
    main()
except SystemExit:
    raise
except Exception as e:  # Blender would print the traceback and still exit 0
    fail("%s: %s" % (type(e).__name__, e))
