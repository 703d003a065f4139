#!/usr/bin/env bash
# Speed against error on seed 000's Table 1 (and the cone-from-metric case): every case at 4
# resolutions on uniform meshes, plus graded + jittered ("nonuniform") meshes, through the real
# pipeline (mesh generator -> static solve -> `shellsim error`). Writes a CSV.
#
#   scripts/speed_vs_error.sh [OUT.csv] [THREADS] [BENDING]
#
# BENDING is the bending model (default: midedge_average, seed 000's own, which docs/accuracy.md's
# Table 1 section documents; scripts/convergence_study.py compares all models).
#
# Columns: case, mesh, edge, vertices, faces, threads, wall_seconds, newton_iterations,
# hausdorff_rel, max_error_rel, rms_error_rel, mean_curvature_rms_error.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
out=${1:-$root/scripts/results/speed_vs_error.csv}
threads=${2:-$(nproc)}
bending=${3:-midedge_average}
mkdir -p "$(dirname "$out")"
cargo build --release --quiet --manifest-path "$root/Cargo.toml"
bin=$root/target/release/shellsim
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
printf '[material]\nthickness = 0.05\nbending = "%s"\n[rest]\ntarget = "mesh"\n' "$bending" > "$work/s.toml"
echo "case,mesh,edge,vertices,faces,threads,wall_seconds,newton_iterations,hausdorff_rel,max_error_rel,rms_error_rel,mean_curvature_rms_error" > "$out"
json() { python3 -c "import json,sys; d=json.load(open(sys.argv[1])); print(','.join(str(d[k]) for k in sys.argv[2:]))" "$@"; }
for case in enlarged_square spherical_cap hyperboloid rhombus cylinder cone; do
  for kind in uniform nonuniform; do
    for edge in 0.1 0.05 0.025 0.0125; do
      if [ "$case" = cone ]; then shape=(annulus --inner 0.3 --radius 1); else shape=(square); fi
      extra=()
      [ "$kind" = nonuniform ] && extra=(--grading 2.5 --jitter 0.2 --seed 5)
      "$bin" mesh "${shape[@]}" --edge "$edge" --program "$case" "${extra[@]}" -o "$work/m.vtk" > /dev/null
      rm -rf "$work/o"
      "$bin" "$work/s.toml" "$work/m.vtk" --out "$work/o" --threads "$threads" -q || true
      frame=$(json "$work/o/summary.json" final_frame)
      "$bin" error "$case" "$work/o/$frame" > "$work/e.json"
      row="$case,$kind,$edge,$(json "$work/o/summary.json" vertices faces threads wall_seconds newton_iterations),$(json "$work/e.json" hausdorff_rel max_error_rel rms_error_rel mean_curvature_rms_error)"
      echo "$row" | tee -a "$out"
    done
  done
done
echo "wrote $out"

# Coupled moisture + mechanics: the wetted paper strip on three meshes, 2 s of
# simulated time. The summary's moisture_seconds is the wall time of the diffusion solve and the
# rest forms; the coupled step costs wall / (wall − moisture_seconds) of the mechanics alone on
# the same steps.
coupled=${out%.csv}_coupled.csv
echo "edge,faces,threads,steps,newton_iterations,wall_seconds,moisture_seconds,ms_per_step,coupled_over_mechanics,diffusion_share" > "$coupled"
for edge in 0.002 0.001 0.0005; do
  "$bin" mesh rectangle --lx 0.06 --ly 0.01 --edge "$edge" -o "$work/strip.vtk" > /dev/null
  rm -rf "$work/o"
  "$bin" "$root/settings/paper_strip_cd.toml" "$work/strip.vtk" --out "$work/o" --threads "$threads" -q \
    --set time.end=2.0 --set time.output_interval=2.0 --set output.format=\"vtu\"
  python3 - "$work/o/summary.json" "$edge" >> "$coupled" <<'PY'
import json, sys
d = json.load(open(sys.argv[1]))
w, m = d["wall_seconds"], d["moisture_seconds"]
print(f'{sys.argv[2]},{d["faces"]},{d["threads"]},{d["steps"]},{d["newton_iterations"]},{w:.3f},{m:.3f},'
      f'{1e3 * w / d["steps"]:.2f},{w / (w - m):.3f},{m / w:.3f}')
PY
  tail -1 "$coupled"
done
echo "wrote $coupled"
