#!/usr/bin/env bash
# End-to-end checks of `snh material`: outputs, JSON, and one-line errors with non-zero exit codes.
# Usage: test_cli.sh PATH_TO_SNH
set -u
SNH="$1"
pass=0
fail=0
# shellcheck source=lib.sh
. "$(dirname "$0")/lib.sh"  # ok, bad, wait_for, expect_exit, expect_error

# check NAME EXIT PATTERN -- ARGS...: snh ARGS exits with EXIT and its output matches PATTERN; EXIT "input":
# refused as bad input (exit 2, one line).
check() {
  local name="$1" want="$2" pattern="$3"
  shift 4
  if [ "$want" = input ]; then expect_error "$name" "$pattern" -- "$SNH" "$@"
  else expect_exit "$want" "$name" "$pattern" -- "$SNH" "$@"; fi
}

# Inspecting energies.
check "snh at rest" 0 "psi = (0|-?[0-9.]+e-1[5-9])$" -- material stable_neo_hookean --stretch 1 1 1
check "snh eigen labels" 0 "flip_2" -- material stable_neo_hookean --mu 1 --lambda 10 --stretch 1.2 0.9 -0.5
check "snh inverted projected" 0 "twist_0 +-18.68 +0$" -- material stable_neo_hookean --stretch 1.2 0.9 -0.5
check "log J undefined" 0 "psi = \+inf: neo_hookean is undefined for J <= 0" -- material neo_hookean --stretch 1 1 -1
check "F column major" 0 "J = -2 " -- material psi_d --F "2 0 0 0 1 0 0 0 -1"
check "youngs/poisson" 0 "nu=0.3000" -- material stvk --youngs 1000 --poisson 0.3 --stretch 1 1 1
check "reparametrize" 0 "reparametrized from linear" -- material stable_neo_hookean_log --reparametrize --stretch 1 1 1
check "json" 0 '"label": "scaling_2"' -- material stable_neo_hookean --json --stretch 1.1 1 1
check "json undefined" 0 '"psi": null' -- material neo_hookean_b --json --stretch 1 1 -1
check "list" 0 "neo_hookean_b +mu/2 \(J\^\(-2/3\) I_C - 3\)" -- material --list
check "stability table" 0 "stable_neo_hookean_log +ok 50/50" -- material --stability --samples 50
check "stability json" 0 '"energy": "corotated"' -- material --stability --json --samples 10
check "help" 0 "--reparametrize" -- material --help
# A muscle: the material plus a fibre along a, with active strain.
check "fibre reversed" 0 "I4 = \|F_e a\|\^2 = 1   sign\(a\^T S a\) = -1   psi_fibre = 4$" -- material stable_neo_hookean --fibre 1 0 0 --fibre-stiffness 2 --stretch -1 1 1
check "fibre eigenvalues" 0 "along the fibre +2 +2$" -- material stable_neo_hookean --fibre 0 0 3 --fibre-stiffness 2 --stretch 1 1 0.5
check "fibre across clamped" 0 "across the fibre +-2 +0$" -- material stable_neo_hookean --fibre 0 0 3 --fibre-stiffness 2 --stretch 1 1 0.5
check "contraction rest" 0 "I4 = \|F_e a\|\^2 = 1 " -- material stable_neo_hookean --fibre 1 0 0 --contraction 0.36 --stretch 0.64 1.25 1.25
check "fibre json" 0 '"model": "quadratic"' -- material stable_neo_hookean --json --fibre 0 1 0 --fibre-model quadratic --stretch 1 1.2 1
check "contraction without fibre" input "--fibre-model, --fibre-stiffness and --contraction need --fibre X Y Z" -- material stable_neo_hookean --contraction 0.2 --stretch 1 1 1
check "contraction 1" input "--contraction must be in \[0, 1\), got 1" -- material stable_neo_hookean --fibre 1 0 0 --contraction 1 --stretch 1 1 1
check "fibre zero" input "--fibre: the direction \(0, 0, 0\) has no length" -- material stable_neo_hookean --fibre 0 0 0 --stretch 1 1 1
check "fibre model" input "--fibre-model must be quadratic or signed_arap, got 'stiff'" -- material stable_neo_hookean --fibre 1 0 0 --fibre-model stiff --stretch 1 1 1

# Errors: one line, non-zero exit.
check "unknown material" input "unknown material 'stable_neohookean' \(known: stable_neo_hookean," -- material stable_neohookean --stretch 1 1 1
check "mu zero" input "mu must be a finite number > 0, got 0" -- material stable_neo_hookean --mu 0 --stretch 1 1 1
check "nu 0.5" input "Poisson's ratio must satisfy -1 < nu < 0.5, got 0.5" -- material stable_neo_hookean --youngs 1 --poisson 0.5 --stretch 1 1 1
check "youngs alone" input "--youngs and --poisson go together" -- material stable_neo_hookean --youngs 1 --stretch 1 1 1
check "F short" input "--F needs 9 numbers" -- material stable_neo_hookean --F "1 0 0 0 1 0 0 0"
check "F nan" input "--F entry 4 is not a finite number: 'nan'" -- material stable_neo_hookean --F "1 0 0 0 nan 0 0 0 1"
check "F and stretch" input "excludes" -- material stable_neo_hookean --F "1 0 0 0 1 0 0 0 1" --stretch 1 1 1
check "no F" input "give exactly one of --F" -- material stable_neo_hookean
check "bad projection" input "--projection must be none, clamp or abs" -- material stable_neo_hookean --stretch 1 1 1 --projection foo
check "stretch inf" input "^snh: error: --stretch: must be a finite number, got inf" -- material stable_neo_hookean --stretch 1 1 inf
check "stretch run nan" input "^snh: error: --stretch: must be a finite number, got nan" -- stretch --stretch nan --out /tmp/snh-never-written
check "render frame -1" input "^snh: error: --frame: must be >= 0, got -1" -- render /tmp/snh-never-written --frame -1
check "no reparam psi_d" input "psi_d cannot be reparametrized" -- material psi_d --reparametrize --stretch 1 1 1
# Issue 13: outside the supported ranges, refused before any work, naming the value (no nan printed).
check "mu 1e300" 2 "^snh: error: mu = 1e\+300 is outside the supported range \[1e-12, 1e\+12\]$" -- material stable_neo_hookean --mu 1e300 --stretch 1 1 1
check "stability mu 1e300" 2 "mu = 1e\+300 is outside the supported range" -- material --stability --mu 1e300
check "lambda 1e-300" 2 "lambda = 1e-300 is outside the supported range" -- material stvk --lambda 1e-300 --stretch 1 1 1
check "F 1e300 I" 2 "^snh: error: --F entry 0 = 1e\+300 is outside the supported range \(0 or \|f\| in \[1e-20, 1e\+20\]\)$" -- material stable_neo_hookean --F "1e300 0 0 0 1e300 0 0 0 1e300"
check "stretch 1e150" 2 "--stretch value 0 = 1e\+150 is outside the supported range" -- material stable_neo_hookean --stretch 1e150 1 1
check "stretch 1e-30" 2 "--stretch value 2 = 1e-30 is outside" -- material stable_neo_hookean --stretch 1 1 1e-30
check "F edge 1e20 finite" 0 "psi = [0-9.]+e\+" -- material stable_neo_hookean --mu 1e12 --lambda 1e12 --F "1e20 0 0 0 1e20 0 0 0 1e20"
check "stretch mu 1e300" 2 "mu = 1e\+300 is outside the supported range" -- stretch --mu 1e300 --out /tmp/snh-never-written

check "no subcommand" 2 "subcommand" --
check "bad option value: one line, exit 2" 2 "^snh: error: --tet-split: bogus not in \{paper,mirrored\} \(see snh --help\)$" -- stretch --tet-split bogus
check "missing option value" 2 "^snh: error: --res: 1 required INT missing" -- stretch --res
check "version" 0 "^snh [0-9]+\.[0-9]+\.[0-9]+$" -- --version

echo "$pass passed, $fail failed"
[ "$fail" -eq 0 ]
