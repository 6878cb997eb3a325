#!/usr/bin/env bash
# The tables of docs/models.md "Stochastic references": how far the closed-form
# models are from their random-walk references, as `facet verify` reports them
# (its section on the random walk), over a sweep no shipped material covers:
#   1. a GGX lobe (height-correlated Smith, energy = kulla_conty) at alpha 0.1,
#      0.3, 0.6 and 1, with F = 1, gold and a dielectric of eta 1.5: the
#      single-scattering albedo, with Kulla-Conty, the walk's, and the
#      BRDF-shaped errors of both;
#   2. layer(coat, base) with a GGX coat of alpha 0.05 and 0.3 at eta 1.33 and
#      1.5 over a white Lambertian base and a gold GGX base (alpha 0.3): the
#      layer's albedo against the layered walk's, and its shape error.
# Prints markdown rows. Expects a built tree (scripts/build.sh); a minute or
# two; writes its materials under build/.
# usage: scripts/stochastic-tables.sh
set -euo pipefail
cd "$(dirname "$0")/.."
facet=build/bin/facet
dir=build/stochastic-tables
mkdir -p "$dir"
gold="conductor(eta = rgb(0.143, 0.374, 1.442), k = rgb(3.983, 2.385, 1.603))"

# The rows of one table of `facet verify`'s walk section (the table after a
# line matching $2): theta_o then the numbers.
rows() {
    "$facet" verify "$1" --no-jit --no-quad --no-physics |
        awk -v heading="$2" '$0 ~ heading {on = 1; next} on && $1 !~ /^[0-9]+$/ && $1 != "theta_o" {on = 0} on && $1 ~ /^[0-9]+$/'
}

echo "| Fresnel | alpha | theta_o | single | + Kulla-Conty | walk (± se) | shape: single | shape: + K-C | walk noise |"
echo "|---|--:|--:|--:|--:|--:|--:|--:|--:|"
for fresnel in none "$gold" "dielectric(1.5)"; do
    name=${fresnel%%(*}
    [ "$name" = conductor ] && name=gold
    for alpha in 0.1 0.3 0.6 1; do
        printf 'material t { ndf = ggx(%s); masking = smith_height_correlated; fresnel = %s; energy = kulla_conty; }\n' \
            "$alpha" "$fresnel" > "$dir/lobe.mat"
        rows "$dir/lobe.mat" "against the random walk" | awk -v f="$name" -v a="$alpha" \
            '{printf "| %s | %s | %s | %s | %s | %s ± %s | %s | %s | %s |\n", f, a, $1, $2, $3, $4, $6, $7, $8, $9}'
    done
done
echo
echo "| coat alpha | eta | base | theta_o | layer | layered walk (± se) | shape error | walk noise |"
echo "|--:|--:|---|--:|--:|--:|--:|--:|"
for alpha in 0.05 0.3; do
    for eta in 1.33 1.5; do
        for base in white gold; do
            if [ $base = white ]; then body="diffuse = lambert(1);"
            else body="ndf = ggx(0.3); masking = smith_height_correlated; fresnel = $gold;"; fi
            printf 'material t { lobe coat { ndf = ggx(%s); masking = smith_height_correlated; fresnel = dielectric(%s); }\n lobe base { %s }\n bsdf = layer(coat, base); }\n' \
                "$alpha" "$eta" "$body" > "$dir/layer.mat"
            rows "$dir/layer.mat" "against the layered random walk" | awk -v a="$alpha" -v e="$eta" -v b="$base" \
                '{printf "| %s | %s | %s | %s | %s | %s ± %s | %s | %s |\n", a, e, b, $1, $2, $3, $5, $6, $7}'
        done
    done
done
