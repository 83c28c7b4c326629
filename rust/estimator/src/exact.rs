//! Exact, order-independent sums of floats: fixed-point superaccumulators.
//!
//! A finite `f64` is an integer mantissa below 2^53 times a power of two between 2^-1074 and
//! 2^971, so the exact sum of any number of them is an integer multiple of 2^-1074: a
//! fixed-point number of about 2 100 bits. [`ExactSum`] keeps it as 64-bit digits, each held in
//! an `i128` word whose upper half is headroom (2^63 additions fit before a word could
//! overflow, so an addition never propagates a carry); adding or removing a value updates two
//! words, and reading rounds once, correctly (to nearest, ties to even). The value read
//! depends only on the multiset of values added, never on their order: the bitwise equality
//! of the one-shot and the incremental estimates rests on this.
//!
//! [`ExactSquares`] does the same for exact squares (the 106-bit square of the mantissa, in
//! units of 2^-2148), and [`population_std`] computes `count·Σx² − (Σx)²` exactly from the two
//! and rounds it once: the spread is as accurate as a double allows, whatever the ratio of
//! the mean to the spread.
//!
//! Infinities and NaNs are counted apart (a removed value is uncounted), as IEEE sums treat
//! them: any NaN gives NaN, infinities of both signs give NaN, else the infinity.

/// Digits of the linear accumulator: bits up to 2^(64·36) · 2^-1074 hold 2^64 values of 2^1024.
const LINEAR_DIGITS: usize = 36;
/// Digits of the square accumulator: 2^-2148 up to 2^64 squares of 2^1024.
const SQUARE_DIGITS: usize = 70;
/// Digits of `count·Σx² − (Σx)²`.
const VARIANCE_DIGITS: usize = 72;
/// Exponent of the unit of the linear accumulator (the smallest subnormal).
const LINEAR_UNIT: i64 = -1074;
/// Exponent of the unit of the square accumulators.
const SQUARE_UNIT: i64 = -2148;
const FRACTION_MASK: u64 = (1 << 52) - 1;
const INFINITY_BITS: u64 = 0x7FF0_0000_0000_0000;

/// A signed fixed-point number as `Σ words[i] · 2^(64 i)` plus the counts of special values.
#[derive(Debug, Clone)]
struct Digits<const N: usize> {
    words: [i128; N],
    /// Every word outside `low..high` is zero (an empty range: the number is zero).
    low: u16,
    high: u16,
    positive_infinities: i64,
    negative_infinities: i64,
    nans: i64,
}

/// The magnitude of a [`Digits`] in canonical 64-bit digits (`digits[low..high]`, the rest 0).
struct Canonical<const N: usize> {
    digits: [u64; N],
    low: usize,
    high: usize,
    negative: bool,
}

impl<const N: usize> Default for Digits<N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize> Digits<N> {
    fn new() -> Self {
        Self {
            words: [0; N],
            low: 0,
            high: 0,
            positive_infinities: 0,
            negative_infinities: 0,
            nans: 0,
        }
    }

    #[inline(always)]
    fn touch(&mut self, low: usize, high: usize) {
        if self.low >= self.high {
            (self.low, self.high) = (low as u16, high as u16);
        } else {
            self.low = self.low.min(low as u16);
            self.high = self.high.max(high as u16);
        }
    }

    /// Adds (or subtracts) `value · 2^(64 digit)`.
    #[inline(always)]
    fn add_wide(&mut self, digit: usize, value: u128, negative: bool) {
        let (low, high) = (i128::from(value as u64), (value >> 64) as i128);
        if negative {
            self.words[digit] -= low;
            self.words[digit + 1] -= high;
        } else {
            self.words[digit] += low;
            self.words[digit + 1] += high;
        }
        self.touch(digit, digit + 2);
    }

    /// Adds `value · 2^bit` (a non-negative number of up to 191 bits from there).
    #[inline]
    fn add_u128_at(&mut self, bit: usize, value: u128) {
        if value == 0 {
            return;
        }
        let (digit, shift) = (bit / 64, bit % 64);
        let low = value << shift;
        let top = if shift == 0 {
            0
        } else {
            value >> (128 - shift)
        };
        self.words[digit] += i128::from(low as u64);
        self.words[digit + 1] += (low >> 64) as i128;
        self.words[digit + 2] += top as i128;
        self.touch(digit, digit + 3);
    }

    /// Counts an infinity (`fraction == 0`) or a NaN; `remove` uncounts it.
    #[cold]
    fn add_special(&mut self, fraction: u64, negative: bool, remove: bool) {
        let step = if remove { -1 } else { 1 };
        if fraction != 0 {
            self.nans += step;
        } else if negative {
            self.negative_infinities += step;
        } else {
            self.positive_infinities += step;
        }
    }

    fn has_specials(&self) -> bool {
        self.nans != 0 || self.positive_infinities != 0 || self.negative_infinities != 0
    }

    /// The special result, if any (NaN, or an infinity).
    fn special_value(&self) -> Option<f64> {
        if self.nans != 0 || (self.positive_infinities != 0 && self.negative_infinities != 0) {
            Some(f64::NAN)
        } else if self.positive_infinities != 0 {
            Some(f64::INFINITY)
        } else if self.negative_infinities != 0 {
            Some(f64::NEG_INFINITY)
        } else {
            None
        }
    }

    /// Adds every word of `other` (`negative`: subtracts).
    fn add_digits(&mut self, other: &Self, negative: bool) {
        let (low, high) = (usize::from(other.low), usize::from(other.high));
        for (word, &value) in self.words[low..high]
            .iter_mut()
            .zip(&other.words[low..high])
        {
            if negative {
                *word -= value;
            } else {
                *word += value;
            }
        }
        if low < high {
            self.touch(low, high);
        }
        let sign = if negative { -1 } else { 1 };
        self.positive_infinities += sign * other.positive_infinities;
        self.negative_infinities += sign * other.negative_infinities;
        self.nans += sign * other.nans;
    }

    /// Carries propagated: the magnitude in digits `0..2^64` and the sign.
    fn canonical(&self) -> Canonical<N> {
        let (low, high) = (usize::from(self.low), usize::from(self.high));
        let mut out = Canonical {
            digits: [0; N],
            low,
            high: low,
            negative: false,
        };
        if low >= high {
            return out;
        }
        let mut carry: i128 = 0;
        for i in low..high {
            let v = self.words[i] + carry;
            out.digits[i] = v as u64;
            carry = v >> 64;
        }
        // |carry| < 2^63: one more digit holds it (two's complement when negative).
        out.digits[high] = carry as u64;
        out.high = high + 1;
        if carry < 0 {
            out.negative = true;
            let mut add = 1u64;
            for digit in &mut out.digits[low..=high] {
                let (v, overflow) = (!*digit).overflowing_add(add);
                *digit = v;
                add = u64::from(overflow);
            }
        }
        out
    }
}

impl<const N: usize> Canonical<N> {
    /// Bit `index` of the magnitude.
    fn bit(&self, index: usize) -> bool {
        (self.digits[index / 64] >> (index % 64)) & 1 == 1
    }

    /// Any bit below `index` set.
    fn any_below(&self, index: usize) -> bool {
        let word = index / 64;
        self.digits[self.low.min(word)..word]
            .iter()
            .any(|&d| d != 0)
            || self.digits[word] & ((1u64 << (index % 64)) - 1) != 0
    }

    /// The magnitude times `2^unit`, correctly rounded (to nearest, ties to even).
    fn round(&self, unit: i64) -> f64 {
        let Some(top) = (self.low..self.high).rev().find(|&i| self.digits[i] != 0) else {
            return 0.0;
        };
        let top_bit = 64 * top + 63 - self.digits[top].leading_zeros() as usize;
        // The lowest bit kept: 53 significant bits, but never below the subnormal grid.
        let grid = (-1074 - unit).max(0) as usize;
        let lsb = top_bit.saturating_sub(52).max(grid);
        let word = lsb / 64;
        let pair = u128::from(self.digits[word])
            | u128::from(self.digits.get(word + 1).copied().unwrap_or(0)) << 64;
        let mut mantissa = ((pair >> (lsb % 64)) as u64) & ((1 << 53) - 1);
        if lsb > 0 && self.bit(lsb - 1) && (mantissa & 1 == 1 || self.any_below(lsb - 1)) {
            mantissa += 1;
        }
        // value = mantissa · 2^exponent; for a normal number the mantissa's top bit is the
        // implicit one, which the addition carries into the exponent field (also when
        // rounding reached 2^53, and from the subnormal range into the normal one).
        let exponent_field = lsb as i64 + unit + 1074;
        if exponent_field > 2046 {
            return f64::INFINITY;
        }
        let bits = ((exponent_field as u64) << 52) + mantissa;
        if bits >= INFINITY_BITS {
            f64::INFINITY
        } else {
            f64::from_bits(bits)
        }
    }

    fn round_signed(&self, unit: i64) -> f64 {
        let magnitude = self.round(unit);
        if self.negative { -magnitude } else { magnitude }
    }
}

/// The exact sum of `f64` values (any order, any number up to 2^63), rounded once when read.
#[derive(Debug, Clone, Default)]
pub(crate) struct ExactSum(Digits<LINEAR_DIGITS>);

impl ExactSum {
    /// Zero.
    pub(crate) fn new() -> Self {
        Self::default()
    }

    #[inline(always)]
    fn update(&mut self, bits: u64, remove: bool) {
        let sign = bits >> 63 == 1;
        let magnitude = bits & !(1 << 63);
        if magnitude >= INFINITY_BITS {
            self.0.add_special(magnitude & FRACTION_MASK, sign, remove);
            return;
        }
        let (position, mantissa) = position_and_mantissa(magnitude);
        if mantissa == 0 {
            return;
        }
        let negative = sign != remove;
        self.0.add_wide(
            position / 64,
            u128::from(mantissa) << (position % 64),
            negative,
        );
    }

    /// Adds the float whose bits these are.
    #[inline(always)]
    pub(crate) fn add_bits(&mut self, bits: u64) {
        self.update(bits, false);
    }

    /// Removes a float added before (by its bits).
    #[inline(always)]
    pub(crate) fn remove_bits(&mut self, bits: u64) {
        self.update(bits, true);
    }

    /// Adds a float.
    #[cfg(test)]
    pub(crate) fn add(&mut self, value: f64) {
        self.add_bits(value.to_bits());
    }

    /// Adds (`negative`: subtracts) another exact sum.
    pub(crate) fn add_sum(&mut self, other: &ExactSum, negative: bool) {
        self.0.add_digits(&other.0, negative);
    }

    /// The sum, correctly rounded.
    pub(crate) fn value(&self) -> f64 {
        match self.0.special_value() {
            Some(special) => special,
            None => self.0.canonical().round_signed(LINEAR_UNIT),
        }
    }
}

/// The exact sum of the squares of `f64` values, for [`population_std`].
#[derive(Debug, Clone, Default)]
pub(crate) struct ExactSquares(Digits<SQUARE_DIGITS>);

impl ExactSquares {
    /// Zero.
    pub(crate) fn new() -> Self {
        Self::default()
    }

    /// Adds the square of the float whose bits these are.
    #[inline(always)]
    pub(crate) fn add_bits(&mut self, bits: u64) {
        let magnitude = bits & !(1 << 63);
        if magnitude >= INFINITY_BITS {
            // The square of ±inf is +inf; of a NaN, a NaN.
            self.0.add_special(magnitude & FRACTION_MASK, false, false);
            return;
        }
        let (position, mantissa) = position_and_mantissa(magnitude);
        if mantissa == 0 {
            return;
        }
        let square = u128::from(mantissa) * u128::from(mantissa); // < 2^106
        let position = 2 * position; // units of 2^-2148
        let (digit, shift) = (position / 64, position % 64);
        let low = u128::from(square as u64) << shift; // < 2^127
        let high = (square >> 64) << shift; // < 2^105
        // square · 2^position = low · 2^(64 digit) + high · 2^(64 (digit + 1)).
        let words = [
            i128::from(low as u64),
            (low >> 64) as i128 + i128::from(high as u64),
            (high >> 64) as i128,
        ];
        let target = &mut self.0.words[digit..digit + 3];
        for (word, value) in target.iter_mut().zip(words) {
            *word += value;
        }
        self.0.touch(digit, digit + 3);
    }

    /// The sum of squares, correctly rounded.
    #[cfg(test)]
    pub(crate) fn value(&self) -> f64 {
        match self.0.special_value() {
            Some(special) => special,
            None => self.0.canonical().round_signed(SQUARE_UNIT),
        }
    }
}

/// Values summed in registers between two flushes: 2^20 mantissas below 2^(53 + 55) stay
/// below 2^128, and their squares below 2^256.
const REGISTER_CHUNK: usize = 1 << 20;
/// Values whose lowest mantissa bit lies at most this many bits below the bound's are summed
/// in registers; smaller ones (below 2^-55 of the bound: rare) go word by word.
const REGISTER_SPAN: usize = 55;

/// The position of the lowest mantissa bit of a finite non-negative float, in units of
/// 2^-1074, and its mantissa.
#[inline(always)]
fn position_and_mantissa(bits: u64) -> (usize, u64) {
    let exponent = (bits >> 52) as usize;
    let fraction = bits & FRACTION_MASK;
    let implicit = u64::from(exponent != 0) << 52;
    (exponent.max(1) - 1, fraction | implicit)
}

/// Adds `values` (float bits) to `sum` and, if given, their squares to `squares`.
///
/// The fast path for the estimator's windows: with every value at most `bound` (a
/// non-negative finite float's bits), values within 2^55 of the bound are summed in
/// registers relative to it (a u128 for the values, two for the squares) and flushed into
/// the exact sums every 2^20 values; the rest (tiny, negative, special or above the bound)
/// go through the exact sums one by one. The result is the same exact sum either way.
pub(crate) fn add_values(
    sum: &mut ExactSum,
    mut squares: Option<&mut ExactSquares>,
    values: impl IntoIterator<Item = u64>,
    bound: u64,
) {
    let with_squares = squares.is_some();
    if bound >= INFINITY_BITS {
        for b in values {
            sum.add_bits(b);
            if let Some(squares) = squares.as_deref_mut() {
                squares.add_bits(b);
            }
        }
        return;
    }
    let top = position_and_mantissa(bound).0;
    let base = top.saturating_sub(REGISTER_SPAN);
    let (mut linear, mut square_low, mut square_high) = (0u128, 0u128, 0u128);
    let mut count = 0;
    let mut flush = |linear: &mut u128, low: &mut u128, high: &mut u128| {
        sum.0.add_u128_at(base, std::mem::take(linear));
        if let Some(squares) = squares.as_deref_mut() {
            squares.0.add_u128_at(2 * base, std::mem::take(low));
            squares.0.add_u128_at(2 * base + 128, std::mem::take(high));
        }
    };
    let mut slow = Vec::new();
    for b in values {
        let (position, mantissa) = position_and_mantissa(b);
        if b > bound || position < base {
            slow.push(b);
            continue;
        }
        let shift = position - base;
        linear += u128::from(mantissa) << shift;
        if with_squares {
            let square = u128::from(mantissa) * u128::from(mantissa); // < 2^106
            let shift = 2 * shift; // ≤ 110
            let low = square << shift;
            let high = (square >> 1) >> (127 - shift);
            let (sum_low, carry) = square_low.overflowing_add(low);
            square_low = sum_low;
            square_high += high + u128::from(carry);
        }
        count += 1;
        if count == REGISTER_CHUNK {
            flush(&mut linear, &mut square_low, &mut square_high);
            count = 0;
        }
    }
    flush(&mut linear, &mut square_low, &mut square_high);
    for b in slow {
        sum.add_bits(b);
        if let Some(squares) = squares.as_deref_mut() {
            squares.add_bits(b);
        }
    }
}

/// Population standard deviation (numpy's `std`) of `count` values from their exact sum and
/// exact sum of squares: `sqrt((count·Σx² − (Σx)²) / count²)` with the numerator exact and
/// rounded once. NaN for no values, or when a value was infinite or NaN (as numpy).
pub(crate) fn population_std(count: usize, sum: &ExactSum, squares: &ExactSquares) -> f64 {
    if count == 0 || sum.0.has_specials() || squares.0.has_specials() {
        return f64::NAN;
    }
    let (s1, s2) = (sum.0.canonical(), squares.0.canonical());
    let mut d = Digits::<VARIANCE_DIGITS>::new();
    let m = count as u128;
    for k in s2.low..s2.high {
        d.add_wide(k, u128::from(s2.digits[k]) * m, s2.negative);
    }
    // (Σx)² in units of 2^-2148: digit i times digit j lands on digit i + j.
    for i in s1.low..s1.high {
        for j in s1.low..s1.high {
            d.add_wide(
                i + j,
                u128::from(s1.digits[i]) * u128::from(s1.digits[j]),
                true,
            );
        }
    }
    let numerator = d.canonical();
    if numerator.negative {
        // Impossible for exact squares (Cauchy–Schwarz); kept finite for robustness.
        return 0.0;
    }
    let Some(top) = (numerator.low..numerator.high)
        .rev()
        .find(|&i| numerator.digits[i] != 0)
    else {
        return 0.0;
    };
    // Scaled by an even power of two to about 1 before rounding, so that a numerator beyond
    // the range of doubles (subnormal or huge values) still gives the right spread.
    let top_bit = (64 * top + 63 - numerator.digits[top].leading_zeros() as usize) as i64;
    let scale = 2 * (-(top_bit + SQUARE_UNIT)).div_euclid(2);
    let n = count as f64;
    let root = (numerator.round(SQUARE_UNIT + scale) / (n * n)).sqrt();
    scale_by_power_of_two(root, -scale / 2)
}

/// `x · 2^exponent`, exact unless the result leaves the normal range.
fn scale_by_power_of_two(mut x: f64, mut exponent: i64) -> f64 {
    while exponent != 0 {
        let step = exponent.clamp(-1000, 1000);
        x *= 2f64.powi(step as i32);
        exponent -= step;
    }
    x
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn sum_of(values: &[f64]) -> f64 {
        let mut s = ExactSum::new();
        for &v in values {
            s.add(v);
        }
        s.value()
    }

    fn finite() -> impl Strategy<Value = f64> {
        prop_oneof![
            any::<u64>().prop_map(f64::from_bits),
            (-1e3f64..1e3),
            (0u64..1 << 52).prop_map(f64::from_bits), // subnormals
        ]
        .prop_filter("finite", |v| v.is_finite())
    }

    /// The rounding error of `a + b` (Knuth's TwoSum), exactly representable.
    fn two_sum(a: f64, b: f64) -> (f64, f64) {
        let s = a + b;
        let bb = s - a;
        (s, (a - (s - bb)) + (b - bb))
    }

    #[test]
    fn known_sums() {
        assert_eq!(sum_of(&[]), 0.0);
        assert_eq!(sum_of(&[0.1, 0.2, 0.3]), 0.6); // fsum([0.1, 0.2, 0.3]) == 0.6
        assert_eq!(sum_of(&[1e100, 1.0, -1e100]), 1.0);
        assert_eq!(sum_of(&[f64::MAX, f64::MAX, -f64::MAX]), f64::MAX);
        assert_eq!(sum_of(&[f64::MAX, f64::MAX]), f64::INFINITY);
        assert_eq!(sum_of(&[-f64::MAX, -f64::MAX]), f64::NEG_INFINITY);
        assert_eq!(sum_of(&[5e-324, 5e-324, 5e-324]), 1.5e-323);
        assert_eq!(sum_of(&[1.0, 2f64.powi(-53)]), 1.0); // tie: to even
        assert_eq!(
            sum_of(&[1.0, 2f64.powi(-53), 2f64.powi(-80)]),
            1.0 + f64::EPSILON
        );
        assert_eq!(sum_of(&[-3.5, 1.25]), -2.25);
        assert!(sum_of(&[1.0, f64::NAN]).is_nan());
        assert!(sum_of(&[f64::INFINITY, f64::NEG_INFINITY]).is_nan());
        assert_eq!(sum_of(&[f64::INFINITY, 1.0]), f64::INFINITY);
        let mut s = ExactSum::new();
        s.add(f64::INFINITY);
        s.remove_bits(f64::INFINITY.to_bits());
        s.add(2.5);
        assert_eq!(s.value(), 2.5);
    }

    #[test]
    fn squares_and_spread() {
        let (mut s, mut q) = (ExactSum::new(), ExactSquares::new());
        let values = [3f64.to_bits(), 4f64.to_bits()];
        add_values(&mut s, Some(&mut q), values, values[1]);
        assert_eq!(q.value(), 25.0);
        assert_eq!(population_std(2, &s, &q), 0.5);
        // A spread far below the mean: numerator exact, so still right.
        let values = [1e8 + 1.0, 1e8 + 2.0, 1e8 + 3.0];
        let (mut s, mut q) = (ExactSum::new(), ExactSquares::new());
        for v in values {
            s.add(v);
            q.add_bits(v.to_bits());
        }
        assert_eq!(population_std(3, &s, &q), (2f64 / 3.0).sqrt());
        // Squares beyond the range of doubles, both ways.
        for scale in [2f64.powi(600), 2f64.powi(-600)] {
            let (mut s, mut q) = (ExactSum::new(), ExactSquares::new());
            for v in [scale, 3.0 * scale] {
                s.add(v);
                q.add_bits(v.to_bits());
            }
            assert_eq!(population_std(2, &s, &q), scale);
        }
        let tiny = 5e-324f64;
        let mut q = ExactSquares::new();
        q.add_bits(tiny.to_bits());
        assert_eq!(q.value(), 0.0); // 2^-2148 rounds to zero
        q.add(1e-160);
        assert_eq!(q.value(), 1e-160 * 1e-160);
    }

    impl ExactSquares {
        fn add(&mut self, v: f64) {
            self.add_bits(v.to_bits());
        }
    }

    /// `scripts/golden/make_exact_sums.py`: Python's exact rational sums and variances.
    #[test]
    fn golden_sums_and_spreads_equal_python_fractions() {
        let path = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/tests/data/golden_exact_sums.json"
        );
        let golden: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
        let float = |v: &serde_json::Value| f64::from_bits(v.as_u64().unwrap());
        for case in golden["cases"].as_array().unwrap() {
            let name = case["name"].as_str().unwrap();
            let bits: Vec<u64> = case["bits"]
                .as_array()
                .unwrap()
                .iter()
                .map(|b| b.as_u64().unwrap())
                .collect();
            let (mut sum, mut squares) = (ExactSum::new(), ExactSquares::new());
            let bound = bits.iter().copied().max().unwrap();
            add_values(&mut sum, Some(&mut squares), bits.iter().copied(), bound);
            assert_eq!(sum.value(), float(&case["fsum"]), "{name}: sum");
            if let Some(exact) = case.get("std").map(float) {
                let got = population_std(bits.len(), &sum, &squares);
                // Rounded twice (the numerator, the quotient) and a square root: within 2 ulps
                // (of the subnormal grid, for subnormal spreads).
                assert!(
                    (got - exact).abs() <= (2.0 * f64::EPSILON * exact).max(1e-323),
                    "{name}: std {got} vs exact {exact}"
                );
                let numpy = float(&case["numpy_std"]);
                eprintln!(
                    "{name}: numpy std off by {:e} relative",
                    (numpy - exact).abs() / exact
                );
            }
        }
    }

    proptest! {
        #[test]
        fn two_values_round_as_ieee_addition(a in finite(), b in finite()) {
            let want = a + b;
            let got = sum_of(&[a, b]);
            prop_assert!(got.to_bits() == want.to_bits() || (got == 0.0 && want == 0.0), "{a} + {b}: {got} vs {want}");
        }

        #[test]
        fn the_rounding_error_of_an_addition_is_exact(a in finite(), b in finite()) {
            let (s, e) = two_sum(a, b);
            prop_assume!(s.is_finite());
            prop_assert_eq!(sum_of(&[a, b, -s]), e);
            prop_assert_eq!(sum_of(&[-s, b, a]), e);
        }

        #[test]
        fn integers_sum_as_i128(values in prop::collection::vec(any::<i64>(), 0..50), scale in -900i32..900) {
            // Integers of 53 bits times a power of two are exact floats, and so is the scaling
            // of the correctly rounded `total as f64` (no overflow, no subnormal).
            let factor = 2f64.powi(scale);
            let ints: Vec<i64> = values.iter().map(|v| v >> 11).collect();
            let floats: Vec<f64> = ints.iter().map(|&v| v as f64 * factor).collect();
            let total: i128 = ints.iter().map(|&v| i128::from(v)).sum();
            prop_assert_eq!(sum_of(&floats), total as f64 * factor);
        }

        #[test]
        fn order_and_removals_do_not_matter(values in prop::collection::vec(finite(), 1..60), extra in prop::collection::vec(finite(), 0..20), seed in any::<u64>()) {
            let mut forward = ExactSum::new();
            for &v in &values { forward.add(v); }
            let mut shuffled = values.clone();
            let mut state = seed | 1;
            for i in (1..shuffled.len()).rev() {
                state ^= state << 13; state ^= state >> 7; state ^= state << 17;
                shuffled.swap(i, (state % (i as u64 + 1)) as usize);
            }
            let mut other = ExactSum::new();
            for &v in &extra { other.add(v); }
            for &v in &shuffled { other.add(v); }
            for &v in extra.iter().rev() { other.remove_bits(v.to_bits()); }
            prop_assert_eq!(forward.value().to_bits(), other.value().to_bits());
            let mut combined = ExactSum::new();
            combined.add_sum(&forward, false);
            combined.add_sum(&forward, true);
            prop_assert_eq!(combined.value(), 0.0);
        }

        #[test]
        fn registers_equal_word_by_word_sums(
            values in prop::collection::vec(prop_oneof![
                finite().prop_map(f64::abs),
                (0.0f64..1e-3),
                Just(0.0),
                (0u64..1 << 52).prop_map(f64::from_bits),
                Just(f64::INFINITY),
                Just(-1.5),
            ], 0..80),
            loose in any::<bool>(),
        ) {
            let bits: Vec<u64> = values.iter().map(|v| v.to_bits()).collect();
            let (mut plain, mut plain_squares) = (ExactSum::new(), ExactSquares::new());
            for &b in &bits {
                plain.add_bits(b);
                plain_squares.add_bits(b);
            }
            // A bound at the largest finite value (some values then take the slow path), or
            // the largest float.
            let finite_max = bits.iter().copied().filter(|&b| b < INFINITY_BITS).max().unwrap_or(0);
            let bound = if loose { f64::MAX.to_bits() } else { finite_max };
            let (mut fast, mut fast_squares) = (ExactSum::new(), ExactSquares::new());
            add_values(&mut fast, Some(&mut fast_squares), bits.iter().copied(), bound);
            prop_assert_eq!(fast.value().to_bits(), plain.value().to_bits());
            prop_assert_eq!(fast_squares.value().to_bits(), plain_squares.value().to_bits());
            let n = bits.len();
            prop_assert_eq!(
                population_std(n, &fast, &fast_squares).to_bits(),
                population_std(n, &plain, &plain_squares).to_bits()
            );
        }

        #[test]
        fn spread_equals_two_pass_std(values in prop::collection::vec(0.0f64..10.0, 1..300), offset in 0.0f64..1e6) {
            let shifted: Vec<f64> = values.iter().map(|v| v + offset).collect();
            let (mut s, mut q) = (ExactSum::new(), ExactSquares::new());
            for v in &shifted {
                s.add(*v);
                q.add_bits(v.to_bits());
            }
            let got = population_std(shifted.len(), &s, &q);
            // Two-pass with an exact mean: accurate to a few ulps of the mean over the spread.
            let mean = s.value() / shifted.len() as f64;
            let want = (shifted.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / shifted.len() as f64).sqrt();
            let tolerance = 1e-12 * want + 1e-15 * offset;
            prop_assert!((got - want).abs() <= tolerance, "{got} vs {want}");
        }
    }
}
