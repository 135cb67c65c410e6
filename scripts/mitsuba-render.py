"""Renders an exported Mitsuba scene: python mitsuba-render.py VARIANT SCENE.xml OUT.exr SPP W H SEED MAX_DEPTH

Writes OUT.exr (linear RGB, float32) and OUT.json (load and render seconds, spp). MAX_DEPTH 3 is
direct light plus one bounce (the reference's quantity), 2 direct light only. Used by
scripts/mitsuba-check.sh.
"""
import json
import sys
import time

import mitsuba as mi

variant, xml, exr, spp, w, h, seed, depth = sys.argv[1:9]
mi.set_variant(variant)
t0 = time.time()
scene = mi.load_file(xml, spp=int(spp), width=int(w), height=int(h), seed=int(seed),
                     max_depth=int(depth))
t1 = time.time()
img = mi.render(scene)
mi.util.write_bitmap(exr, img)
t2 = time.time()
with open(exr[:-4] + ".json", "w") as f:
    json.dump({"load": t1 - t0, "render": t2 - t1, "spp": int(spp), "width": int(w),
               "height": int(h), "seed": int(seed), "max_depth": int(depth), "variant": variant}, f)
print(f"mitsuba {exr}: {w}x{h}, {spp} spp, max_depth {depth}: load {t1 - t0:.1f} s, "
      f"render {t2 - t1:.1f} s")
