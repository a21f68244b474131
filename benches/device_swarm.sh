#!/usr/bin/env bash
# The swarm figures a many-core machine shows, in one run that prints everything (and tees each
# table into $OUT when that is set): every built-in and the rendezvous example in swarm mode at
# 100,000 robots on 1-16 threads and at 1,000,000 robots on 1 and 16, unprofiled (the scaling the
# cost issue asks for); at 1,000,000 on 16 threads, the threaded robots decided in one call (the
# A/B of `SwarmRobot.threaded`) and where each step's time goes (cProfile, which slows Python);
# and hrvo-circle's 100 steps at 1,000,000 robots with its peak RSS.
# First, when WHEEL_DIR holds the `wake` example (`cargo build --release -p dream-core --example
# wake && cp target/release/examples/wake .device/`), what waking the kernels' threads costs on 2-16
# of them: the figure behind `parallel::worth_spreading`'s threshold (0.2 ms of work, set on 2 cores).
#   bash benches/device_swarm.sh [WHEEL_DIR]   # installs DREAM's wheel from WHEEL_DIR first, if any
#   N1=1000 N2=10000 bash benches/device_swarm.sh   # a quick try of the script at small sizes
set -u
wheels=${1:-.device}
out=${OUT:-/tmp/device-out}
mkdir -p "$out"
if ls "$wheels"/*.whl >/dev/null 2>&1; then
    python3 -m pip install -q --no-index --no-deps --no-compile --upgrade --target /tmp/site "$wheels"/*.whl && export PYTHONPATH=/tmp/site
fi
export PYTHONUNBUFFERED=1
echo "cores $(nproc); $(uptime); $(python3 --version); $(date -u +%FT%TZ)"
if [ -x "$wheels/wake" ]; then
    for threads in 2 4 16; do RAYON_NUM_THREADS=$threads "$wheels/wake"; done | tee "$out/wake.md"
fi
python3 benches/bench_swarm.py -n ${N1:-100000} --threads 1 2 4 8 16 --steps 44 --warm-up 32 --timeout 120 | tee "$out/swarm-100k.md"
python3 benches/bench_swarm.py -n ${N2:-1000000} --threads 1 16 --steps 38 --warm-up 32 --timeout 240 | tee "$out/swarm-1m.md"
python3 benches/bench_swarm.py -n ${N2:-1000000} -e hrvo-circle line-consensus affine-formation --threads 16 \
    --steps 38 --warm-up 32 --timeout 240 --one-call | tee "$out/swarm-1m-one-call.md"
python3 benches/bench_swarm.py -n ${N2:-1000000} --threads 16 --steps 38 --warm-up 32 --timeout 240 --breakdown 10 \
    | tee "$out/swarm-1m-profiled.md"
echo "== hrvo-circle --swarm -n 1000000 --steps 100, every core"
timeout 240 python3 - "${N2:-1000000}" <<'PY' | tee "$out/hrvo-1m-100.txt"
import resource, sys, time
import dream
from dream.experiments import find

start = time.perf_counter()
result = dream.run(find("hrvo-circle"), n=int(sys.argv[1]), steps=100, backend="fast", swarm=True)
rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 2**20
print(f"steps {result.steps}, collisions {result.collisions}, wall {time.perf_counter() - start:.1f} s "
      f"(stepping {result.wall_time:.1f} s), peak RSS {rss:.2f} GiB")
PY
echo "done $(date -u +%FT%TZ); $(uptime)"
