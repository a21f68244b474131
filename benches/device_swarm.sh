#!/usr/bin/env bash
# The swarm engine's figures on a many-core machine, in one run: the step at 100,000 robots on
# 1-16 threads, at 1,000,000 robots, and a 1,000,000-robot rendezvous run with its peak RSS.
#   bash benches/device_swarm.sh [WHEEL_DIR]   # installs DREAM's wheel from WHEEL_DIR first, if any
set -u
wheels=${1:-.device}
if ls "$wheels"/*.whl >/dev/null 2>&1; then
    python3 -m pip install -q --no-index --no-deps --no-compile --target /tmp/site "$wheels"/*.whl && export PYTHONPATH=/tmp/site
fi
export PYTHONUNBUFFERED=1
echo "cores $(nproc); $(uptime); $(python3 --version); $(date -u +%FT%TZ)"
for threads in 1 2 4 8 16; do
    echo "== RAYON_NUM_THREADS=$threads"
    RAYON_NUM_THREADS=$threads python3 benches/bench_engine.py 100000
done
for threads in 4 16; do
    echo "== RAYON_NUM_THREADS=$threads"
    RAYON_NUM_THREADS=$threads python3 benches/bench_engine.py 1000000
done
echo "== dream run examples/rendezvous.py --swarm -n 1000000 --steps 30 --backend fast"
python3 - <<'PY'
import resource, time
import dream
from dream.experiments import find

start = time.perf_counter()
result = dream.run(find("examples/rendezvous.py"), n=1_000_000, steps=30, backend="fast", swarm=True)
rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
print(f"steps {result.steps}, collisions {result.collisions}, wall {time.perf_counter() - start:.1f} s "
      f"(stepping {result.wall_time:.1f} s), peak RSS {rss:,.0f} MiB")
PY
