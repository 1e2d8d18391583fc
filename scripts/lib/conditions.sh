# The six rendering conditions that scripts/coverage and scripts/zero-error draw
# their seeded clips from, as "label|render arguments" (sourced, not run).
# shellcheck disable=SC2034
conditions=(
  "dark plate, noise 1|--plate dark --noise 1"
  "light plate, noise 2|--plate light --noise 2"
  "dark plate, blur 0.8 px, noise 1|--plate dark --blur 0.8 --noise 1"
  "dark plate, flicker 0.05, noise 1|--plate dark --flicker 0.05 --noise 1"
  "dark plate, drift 20 px/s, noise 1|--plate dark --drift 20 --noise 1"
  "two-view, noise 1|--two-view --noise 1"
)
