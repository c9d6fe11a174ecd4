"""The launch plans of path_queue "auto" (pathtrace.rendering.queue_plans.AUTO_PLANS) timed over whole renders
(docs/notes/performance-2026-11.md, 2026-11-27: the queue chosen by trial renders):

  python docs/notes/studies/queue_plans_study.py SCENE... [--device gpu] [--size WxH] [--spp N] [--rounds N]

Each scene is rendered with max depth 8 and next-event estimation, no roulette, with each plan in
turn (after a launch that builds and warms its kernels), in each round. Prints one JSON line per
render: the plan, the render's seconds and the image's mean, which is the same for every plan."""

import argparse
import json
import time

from pathtrace.device.opencl import choose_device
from pathtrace.rendering.queue_plans import AUTO_PLANS, PLAN_NAMES
from pathtrace.rendering.renderer import Renderer
from pathtrace.scene import load_scene
from pathtrace.rendering.choices import PATH_QUEUE_AUTO


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("scenes", nargs="+")
    p.add_argument("--device", default="gpu")
    p.add_argument("--size", default="1920x1080")
    p.add_argument("--spp", type=int, default=500)
    p.add_argument("--rounds", type=int, default=2)
    args = p.parse_args()
    backend = choose_device(args.device)
    width, height = (int(v) for v in args.size.split("x"))
    for k in range(args.rounds):
        for name in args.scenes:
            scene = load_scene(name).with_settings(max_depth=8, russian_roulette="off", nee=True,
                                                   path_queue=PATH_QUEUE_AUTO)
            for plan in AUTO_PLANS:
                r = Renderer(backend, scene, width, height)
                r.use_queue_plan(plan)
                r.add_samples(4)
                r.finish()
                r.reset()
                start = time.perf_counter()
                r.add_samples(args.spp)
                r.finish()
                seconds = time.perf_counter() - start
                print(json.dumps(dict(round=k, scene=scene.name, plan=PLAN_NAMES[plan],
                                      seconds=round(seconds, 4), mean=float(r.mean().mean()))), flush=True)


if __name__ == "__main__":
    main()
