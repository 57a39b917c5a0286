//! A branch-free `exp` that the compiler vectorises, for the DMP bases and phases.
//!
//! The bases cost one `exp` per basis near each sample (about 8 per sample with the default
//! width), which through libm's scalar `exp` was a fifth of a fit. This one reduces
//! `x = (64 m + j) ln 2 / 64 + r` with `|r| ≤ ln 2 / 128` (Cody-Waite, two-part constant), takes
//! `2^(j/64)` from a table (correctly rounded), `exp(r)` from its degree-5 Taylor polynomial
//! (truncation below `4e-17` relative) and `2^m` from the bits. It agrees with libm's `exp` to within 2 ulp (tested below) for
//! `x ∈ [−708, 709]`; arguments outside that range are clamped to it, so it never returns 0 or
//! infinity (callers pass arguments within `[−745, 709]` only where that does not matter).

/// `1.5 · 2^52`: adding it rounds a double of magnitude below `2^51` to an integer, which then
/// sits in the low bits of the sum's mantissa (two's complement).
const SHIFTER: f64 = 6_755_399_441_055_744.0;
/// `64 / ln 2`.
const INV_STEP: f64 = 92.332_482_616_893_66;
/// `ln 2 / 64` split so that `k · STEP_HI` is exact for `|k| < 2^32`.
const STEP_HI: f64 = 0.010_830_417_275_428_772;
const STEP_LO: f64 = 7.420_820_373_486_988e-9;
/// `2^(j/64)`, `j = 0..64`, correctly rounded.
#[allow(clippy::excessive_precision, clippy::unreadable_literal)]
const TABLE: [f64; 64] = [
    1.0,
    1.0108892860517005,
    1.0218971486541166,
    1.0330248790212284,
    1.0442737824274138,
    1.0556451783605572,
    1.0671404006768237,
    1.0787607977571199,
    1.0905077326652577,
    1.102382583307841,
    1.1143867425958924,
    1.1265216186082418,
    1.1387886347566916,
    1.1511892299529827,
    1.1637248587775775,
    1.1763969916502812,
    1.189207115002721,
    1.202156731452703,
    1.215247359980469,
    1.22848053610687,
    1.241857812073484,
    1.255380757024691,
    1.2690509571917332,
    1.2828700160787783,
    1.2968395546510096,
    1.3109612115247644,
    1.3252366431597413,
    1.339667524053303,
    1.3542555469368927,
    1.3690024229745905,
    1.383909881963832,
    1.3989796725383112,
    std::f64::consts::SQRT_2,
    1.42961333839197,
    1.4451808069770467,
    1.460917794180647,
    1.4768261459394993,
    1.4929077282912648,
    1.5091644275934228,
    1.5255981507445384,
    1.5422108254079407,
    1.559004400237837,
    1.5759808451078865,
    1.593142151342267,
    1.6104903319492543,
    1.6280274218573478,
    1.645755478153965,
    1.6636765803267364,
    1.681792830507429,
    1.7001063537185235,
    1.718619298122478,
    1.7373338352737062,
    1.7562521603732995,
    1.7753764925265212,
    1.7947090750031072,
    1.8142521755003989,
    1.8340080864093424,
    1.8539791250833855,
    1.8741676341103,
    1.8945759815869656,
    1.9152065613971474,
    1.9360617934922943,
    1.9571441241754002,
    1.978456026387951,
];

/// `exp(x)` within 2 ulp of libm's for `x ∈ [−708, 709]` (clamped to that range).
#[inline(always)]
pub(crate) fn exp(x: f64) -> f64 {
    // `if` rather than `clamp`: compiles to min/max, which vectorise.
    let x = if x < -708.0 { -708.0 } else { x };
    let x = if x > 709.0 { 709.0 } else { x };
    let shifted = x * INV_STEP + SHIFTER;
    let k = shifted - SHIFTER;
    let r = (x - k * STEP_HI) - k * STEP_LO;
    // exp(r) − 1 to r⁵/5!.
    let q = r * (1.0 + r * (0.5 + r * (1.0 / 6.0 + r * (1.0 / 24.0 + r * (1.0 / 120.0)))));
    let bits = shifted.to_bits();
    let table = TABLE[(bits & 63) as usize];
    // The bits above the table index hold `m = ⌊k / 64⌋`; `m + 1023` shifted into the exponent
    // field is `2^m` for `m ∈ [−1022, 1023]`.
    let scale = f64::from_bits(((bits >> 6) << 52).wrapping_add(1023 << 52));
    (table + table * q) * scale
}

/// `exp` of every element in place (vectorised).
#[inline]
pub(crate) fn exp_in_place(values: &mut [f64]) {
    for v in values.iter_mut() {
        *v = exp(*v);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn agrees_with_libm_within_2_ulp() {
        let mut worst = 0.0f64;
        let mut check = |x: f64| {
            let (ours, libm) = (exp(x), x.exp());
            let ulp = (libm.to_bits() as i64 - ours.to_bits() as i64).abs();
            assert!(ulp <= 2, "exp({x}): {ours} vs libm {libm} ({ulp} ulp)");
            worst = worst.max(ulp as f64);
        };
        // A dense sweep over the bases' range, then the whole normal range.
        for k in 0..=400_000 {
            check(-40.0 + 50.0 * k as f64 / 400_000.0);
        }
        for k in 0..=200_000 {
            check(-708.0 + 1417.0 * k as f64 / 200_000.0);
        }
        for x in [
            0.0,
            -0.0,
            1e-300,
            -1e-300,
            1e-17,
            std::f64::consts::LN_2,
            -std::f64::consts::LN_2 / 2.0,
        ] {
            check(x);
        }
        eprintln!("largest difference from libm's exp: {worst} ulp");
        assert_eq!(exp(0.0), 1.0);
        assert!(exp(-1e9) > 0.0 && exp(1e9).is_finite());
    }
}
