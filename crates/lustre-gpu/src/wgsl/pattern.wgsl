// module pattern: the per-pixel row lattice of the slope-space Gaussian (ours).
// CPU twins: lustre_shade::pattern::{gauss_quantile, lattice_rows, row_length}. Equations:
// x = erfinv(2u − 1), the quantile of the marginal e^{−x²}/√π (Giles 2011, single precision);
// rows k = round(√(budget / ratio)) clamped to 1 ..= budget; row j holds ⌊budget/k⌋ cells plus
// one for the budget mod k rows nearest the centre.

// pattern::gauss_quantile: erfinv(2u − 1), Giles' single-precision polynomial.
fn gauss_quantile(u_in: f32) -> f32 {
    let x = clamp(2.0 * clamp(u_in, 1e-7, 1.0 - 1e-7) - 1.0, -1.0, 1.0);
    let w0 = -log((1.0 - x) * (1.0 + x));
    var p: f32;
    if (w0 < 5.0) {
        let w = w0 - 2.5;
        p = 2.81022636e-08;
        p = 3.43273939e-07 + p * w;
        p = -3.5233877e-06 + p * w;
        p = -4.39150654e-06 + p * w;
        p = 0.00021858087 + p * w;
        p = -0.00125372503 + p * w;
        p = -0.00417768164 + p * w;
        p = 0.246640727 + p * w;
        p = 1.50140941 + p * w;
    } else {
        let w = sqrt(w0) - 3.0;
        p = -0.000200214257;
        p = 0.000100950558 + p * w;
        p = 0.00134934322 + p * w;
        p = -0.00367342844 + p * w;
        p = 0.00573950773 + p * w;
        p = -0.0076224613 + p * w;
        p = 0.00943887047 + p * w;
        p = 1.00167406 + p * w;
        p = 2.83297682 + p * w;
    }
    return p * x;
}

// pattern::lattice_rows: round(√(budget / ratio)) clamped to 1 ..= budget.
fn lattice_rows(budget: u32, ratio: f32) -> u32 {
    var r = ratio;
    if (!(r >= 1.0)) {
        r = 1.0;
    }
    let k = round(sqrt(f32(budget) / r));
    return u32(clamp(k, 1.0, f32(max(budget, 1u))));
}

// pattern::row_length: ⌊budget/rows⌋ plus one for the budget mod rows rows nearest the centre
// (order c, c−1, c+1, … ).
fn row_length(budget: u32, rows: u32, j: u32) -> u32 {
    let base = budget / rows;
    let extra = budget % rows;
    var rank: u32;
    if (rows % 2u == 1u) {
        let c = (rows - 1u) / 2u;
        if (j == c) {
            rank = 0u;
        } else if (j < c) {
            rank = 2u * (c - j) - 1u;
        } else {
            rank = 2u * (j - c);
        }
    } else {
        let c0 = rows / 2u - 1u;
        if (j <= c0) {
            rank = 2u * (c0 - j);
        } else {
            rank = 2u * (j - c0 - 1u) + 1u;
        }
    }
    return base + select(0u, 1u, rank < extra);
}
