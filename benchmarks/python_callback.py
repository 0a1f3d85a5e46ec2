#!/usr/bin/env python3
"""A scene run from Python with a callback at every step that reads the needle's force: the worst case of the Python
module's overhead, timed against `mtled run` on the same scene (docs/python.md, Speed):

    hyperfine -w 1 -r 11 \\
      'env PYTHONPATH=build/python /usr/bin/python3 benchmarks/python_callback.py share/scenes/needle_small_sample.json /tmp/python' \\
      'build/bin/mtled run share/scenes/needle_small_sample.json -o /tmp/cli --threads 2 --log-level warn --no-progress'

Usage: python_callback.py SCENE OUTPUT [THREADS]
"""
import sys

import mtled

scene, output = sys.argv[1], sys.argv[2]
threads = int(sys.argv[3]) if len(sys.argv) > 3 else 2
forces = []
run = mtled.run(mtled.Scene.load(scene), output, threads=threads, every=1,
                callback=lambda step: forces.append(step.needle["force"]))
assert run.status == "ok" and len(forces) == run.summary["steps"], (run.status, len(forces))
