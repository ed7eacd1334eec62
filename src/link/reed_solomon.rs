//! Reed–Solomon codes over GF(2⁸): the forward error correction of frames to the firmware
//! (`docs/protocol.md` §1).
//!
//! The code is RS(255, 239) — 16 parity bytes per block, up to 8 wrong bytes per block
//! corrected, as in ITU-T G.709 — shortened to the block's length. Its conventions are the
//! common ones (and those of Python's `reedsolo` package, against which the parity is tested):
//! the field GF(2⁸) modulo x⁸ + x⁴ + x³ + x² + 1 (0x11D) with α = 2, the generator polynomial
//! g(x) = (x − α⁰)(x − α¹)…(x − α¹⁵) (first consecutive root α⁰), systematic: a block is its
//! data followed by the 16 parity bytes, the first byte the coefficient of the highest power.
//!
//! Decoding is the textbook one (Blahut, *Algebraic Codes for Data Transmission*, 2003, §7):
//! the 16 syndromes S_j = r(αʲ), the error-locator polynomial Λ by Berlekamp–Massey, its roots
//! by Chien search over the block's own positions, the error values by Forney's formula. A
//! block with more than 8 wrong bytes is reported uncorrectable (or, rarely, miscorrected: the
//! frame's CRC, checked afterwards, catches that).
//!
//! The syndromes come from the parity: the data are encoded again and the difference with the
//! received parity is r(x) mod g(x), whose values at the roots of g are the syndromes. A clean
//! block costs one encoding (16 table look-ups a byte), and nothing else.
//!
//! Every table look-up is checked (`get`), and nothing here allocates or panics.

/// Parity bytes per block (2t).
pub const PARITY: usize = 16;
/// Wrong bytes a block can have and still be corrected (t).
pub const CORRECTABLE: usize = PARITY / 2;
/// Longest block: data and parity (2⁸ − 1).
pub const MAX_BLOCK: usize = 255;
/// Most data bytes in one block.
pub const MAX_DATA: usize = MAX_BLOCK - PARITY;

/// x⁸ + x⁴ + x³ + x² + 1, the field's primitive polynomial.
const PRIMITIVE: u16 = 0x11D;

/// Powers and logarithms of α. Powers repeat after 255 (α²⁵⁵ = 1): one period is kept, and a
/// sum of logarithms is reduced modulo 255 (a table twice as long, read without the reduction,
/// took 64 bytes more of the firmware image, reductions counted).
struct Tables {
    exp: [u8; 255],
    log: [u8; 256],
}

// Evaluated only at compile time (the initializers of `GF` and `GENERATOR_LOGS`): an index out
// of bounds here fails the build, never the firmware.
#[allow(clippy::indexing_slicing)]
const fn tables() -> Tables {
    let mut t = Tables {
        exp: [0; 255],
        log: [0; 256],
    };
    let mut x: u16 = 1;
    let mut i = 0;
    while i < 255 {
        t.exp[i] = x as u8;
        t.log[x as usize] = i as u8;
        x <<= 1;
        if x & 0x100 != 0 {
            x ^= PRIMITIVE;
        }
        i += 1;
    }
    t
}

static GF: Tables = tables();

/// αⁱ.
fn exp(i: usize) -> u8 {
    GF.exp.get(i % 255).copied().unwrap_or(0)
}

/// log_α(a) for a ≠ 0 (0 for a = 0, which callers test first).
fn log(a: u8) -> usize {
    usize::from(GF.log.get(usize::from(a)).copied().unwrap_or(0))
}

fn mul(a: u8, b: u8) -> u8 {
    if a == 0 || b == 0 {
        0
    } else {
        exp(log(a) + log(b))
    }
}

/// a · αᵏ, k < 256.
fn mul_exp(a: u8, k: usize) -> u8 {
    if a == 0 {
        0
    } else {
        exp(log(a) + k)
    }
}

/// 1 / a for a ≠ 0.
fn inv(a: u8) -> u8 {
    exp(255 - log(a))
}

/// The generator polynomial's coefficients after the leading 1, highest power first:
/// g(x) = x¹⁶ + g[0] x¹⁵ + … + g[15].
// Evaluated only at compile time (the initializers of `GF` and `GENERATOR_LOGS`): an index out
// of bounds here fails the build, never the firmware.
#[allow(clippy::indexing_slicing)]
const fn generator() -> [u8; PARITY] {
    let t = tables();
    // g starts as 1 and is multiplied by (x + αⁱ) for i = 0 .. 15; coefficients lowest power
    // first here, turned round at the end.
    let mut g = [0u8; PARITY + 1];
    g[0] = 1;
    let mut i = 0;
    while i < PARITY {
        let root = t.exp[i];
        let mut k = i + 1;
        while k > 0 {
            // new g_k = g_{k−1} + root · g_k
            let prod = if g[k] == 0 {
                0
            } else {
                t.exp[(t.log[g[k] as usize] as usize + t.log[root as usize] as usize) % 255]
            };
            g[k] = g[k - 1] ^ prod;
            k -= 1;
        }
        g[0] = if g[0] == 0 {
            0
        } else {
            t.exp[(t.log[g[0] as usize] as usize + t.log[root as usize] as usize) % 255]
        };
        i += 1;
    }
    // g[PARITY] is the leading 1; g[PARITY − 1 − j] is the coefficient of x^(15 − j).
    let mut out = [0u8; PARITY];
    let mut j = 0;
    while j < PARITY {
        out[j] = g[PARITY - 1 - j];
        j += 1;
    }
    out
}

/// The logarithms of the generator's coefficients (all are non-zero; tested).
// Evaluated only at compile time (the initializers of `GF` and `GENERATOR_LOGS`): an index out
// of bounds here fails the build, never the firmware.
#[allow(clippy::indexing_slicing)]
const fn generator_logs() -> [u8; PARITY] {
    let t = tables();
    let g = generator();
    let mut out = [0u8; PARITY];
    let mut j = 0;
    while j < PARITY {
        out[j] = t.log[g[j] as usize];
        j += 1;
    }
    out
}

const GENERATOR_LOGS: [u8; PARITY] = generator_logs();

/// The parity of `data` (the remainder of data(x)·x¹⁶ divided by g(x)), highest power first:
/// the 16 bytes that follow the data in a block.
pub fn parity(data: impl IntoIterator<Item = u8>) -> [u8; PARITY] {
    // The division's register, byte k (the coefficient of x^(15 − k)) in bits 8k .. 8k + 8.
    let mut reg = 0u128;
    for d in data {
        let feedback = d ^ reg as u8;
        // Shift by one byte, then add feedback · g(x): nothing for a zero feedback.
        reg >>= 8;
        if feedback == 0 {
            continue;
        }
        // αᶠ⁺ᵍ for f = log(feedback) and every g.
        let f = log(feedback);
        let mut next = reg.to_le_bytes();
        for (n, &g) in next.iter_mut().zip(GENERATOR_LOGS.iter()) {
            *n ^= exp(f + usize::from(g));
        }
        reg = u128::from_le_bytes(next);
    }
    reg.to_le_bytes()
}

/// feedback · g(x) for every feedback byte, as [`parity`]'s register (byte k in bits 8k ..
/// 8k + 8): one XOR a data byte instead of 16 look-ups. 4 KiB, for the encoder, which only
/// the host runs: the firmware decodes (with [`parity`]) and does not link this table.
static FEEDBACK_ROWS: [u128; 256] = feedback_rows();

// Evaluated only at compile time (the initializer of `FEEDBACK_ROWS`): an index out of bounds
// here fails the build.
#[allow(clippy::indexing_slicing)]
const fn feedback_rows() -> [u128; 256] {
    let t = tables();
    let mut rows = [0u128; 256];
    let mut f = 1;
    while f < 256 {
        let log_f = t.log[f] as usize;
        let mut row = 0u128;
        let mut k = 0;
        while k < PARITY {
            row |= (t.exp[(log_f + GENERATOR_LOGS[k] as usize) % 255] as u128) << (8 * k);
            k += 1;
        }
        rows[f] = row;
        f += 1;
    }
    rows
}

/// [`parity`] by a table of 256 rows: the same bytes, for the encoder on the host, where every
/// frame to the firmware is encoded (a sweep encodes millions).
pub fn parity_by_table(data: impl IntoIterator<Item = u8>) -> [u8; PARITY] {
    let mut reg = 0u128;
    for d in data {
        let feedback = d ^ reg as u8;
        reg = (reg >> 8)
            ^ FEEDBACK_ROWS
                .get(usize::from(feedback))
                .copied()
                .unwrap_or(0);
    }
    reg.to_le_bytes()
}

/// A received block, as the frame decoder lays it out (data bytes interleaved with other
/// blocks', parity at the end): `size` bytes, read and corrected by position in the block.
pub trait Block {
    /// Bytes in the block, parity included (≤ [`MAX_BLOCK`]).
    fn size(&self) -> usize;
    /// Byte `i` of the block (`i < size`).
    fn byte(&self, i: usize) -> u8;
    /// XORs `error` into byte `i`.
    fn correct(&mut self, i: usize, error: u8);
}

/// More wrong bytes than the code corrects.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Uncorrectable;

/// Corrects `block` in place; the number of bytes corrected (0: it was clean), or
/// [`Uncorrectable`] (the block is then unchanged).
pub fn correct(block: &mut impl Block) -> Result<usize, Uncorrectable> {
    let n = block.size();
    if !(PARITY + 1..=MAX_BLOCK).contains(&n) {
        return Err(Uncorrectable);
    }
    let data = n - PARITY;
    let mut rem = parity((0..data).map(|i| block.byte(i)));
    for (k, r) in rem.iter_mut().enumerate() {
        *r ^= block.byte(data + k);
    }
    if rem.iter().all(|&r| r == 0) {
        return Ok(0);
    }
    // S_j = r(α^j) = rem(α^j), j = 0 .. 15.
    let mut s = [0u8; PARITY];
    for (j, sj) in s.iter_mut().enumerate() {
        *sj = rem.iter().fold(0u8, |acc, &r| mul_exp(acc, j) ^ r);
    }
    let (lambda, degree) = berlekamp_massey(&s)?;
    // Ω(x) = S(x) Λ(x) mod x¹⁶ (both lowest power first).
    let mut omega = [0u8; PARITY];
    for (i, o) in omega.iter_mut().enumerate() {
        for (k, &l) in lambda.iter().enumerate().take(i + 1) {
            *o ^= mul(l, s.get(i - k).copied().unwrap_or(0));
        }
    }
    // Chien search over the block's positions: byte i is the coefficient of x^(n−1−i), so its
    // locator is X = α^(n−1−i); it is wrong where Λ(X⁻¹) = 0. Each term Λ_k X^(−k) is kept as
    // its logarithm, which grows by k from one position to the next (X⁻¹ gains a factor α).
    let mut terms = [None::<usize>; CORRECTABLE + 1];
    let first = 255 - (n - 1); // log of X⁻¹ at i = 0, n ≤ 255
    for (k, (t, &l)) in terms.iter_mut().zip(lambda.iter()).enumerate() {
        if l != 0 {
            *t = Some((log(l) + k * first) % 255);
        }
    }
    let mut found = [(0u8, 0u8); CORRECTABLE];
    let mut roots = 0;
    for i in 0..n {
        let mut sum = 0u8;
        for (k, t) in terms.iter_mut().enumerate() {
            if let Some(e) = t {
                sum ^= exp(*e);
                *e += k;
                if *e >= 255 {
                    *e -= 255;
                }
            }
        }
        if sum != 0 {
            continue;
        }
        let p = n - 1 - i;
        let x_inv = exp(255 - p);
        // Forney, first root α⁰: e = X · Ω(X⁻¹) / Λ'(X⁻¹).
        let denominator = derivative_at(&lambda, x_inv);
        if denominator == 0 {
            return Err(Uncorrectable);
        }
        let e = mul(mul_exp(eval(&omega, x_inv), p), inv(denominator));
        let slot = found.get_mut(roots).ok_or(Uncorrectable)?;
        *slot = (i as u8, e);
        roots += 1;
    }
    if roots != degree {
        return Err(Uncorrectable);
    }
    for &(i, e) in found.iter().take(roots) {
        block.correct(usize::from(i), e);
    }
    Ok(roots)
}

/// Berlekamp–Massey: the error locator Λ (lowest power first, Λ₀ = 1) of the syndromes and
/// its degree, or [`Uncorrectable`] if that is more than [`CORRECTABLE`].
fn berlekamp_massey(s: &[u8; PARITY]) -> Result<([u8; CORRECTABLE + 1], usize), Uncorrectable> {
    let mut c = [0u8; PARITY + 1];
    let mut b = [0u8; PARITY + 1];
    c[0] = 1;
    b[0] = 1;
    let mut l = 0usize;
    let mut m = 1usize;
    let mut last = 1u8;
    for n in 0..PARITY {
        let mut d = s.get(n).copied().unwrap_or(0);
        for i in 1..=l.min(n) {
            d ^= mul(
                c.get(i).copied().unwrap_or(0),
                s.get(n - i).copied().unwrap_or(0),
            );
        }
        if d == 0 {
            m += 1;
            continue;
        }
        let coef = mul(d, inv(last));
        let before = c;
        for (i, &bi) in b.iter().enumerate() {
            if let Some(ci) = c.get_mut(i + m) {
                *ci ^= mul(coef, bi);
            }
        }
        if 2 * l <= n {
            l = n + 1 - l;
            b = before;
            last = d;
            m = 1;
        } else {
            m += 1;
        }
    }
    if l > CORRECTABLE || c.iter().skip(CORRECTABLE + 1).any(|&x| x != 0) {
        return Err(Uncorrectable);
    }
    let mut lambda = [0u8; CORRECTABLE + 1];
    for (o, &ci) in lambda.iter_mut().zip(c.iter()) {
        *o = ci;
    }
    Ok((lambda, l))
}

/// p(x) for p lowest power first.
fn eval(p: &[u8], x: u8) -> u8 {
    p.iter().rev().fold(0u8, |acc, &c| mul(acc, x) ^ c)
}

/// Λ'(x): in characteristic 2 the formal derivative keeps the odd powers, each lowered by one.
fn derivative_at(lambda: &[u8], x: u8) -> u8 {
    let x2 = mul(x, x);
    let odd = lambda.iter().skip(1).step_by(2);
    // Λ₁ + Λ₃ x² + Λ₅ x⁴ + …
    odd.rev().fold(0u8, |acc, &c| mul(acc, x2) ^ c)
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use proptest::prelude::*;
    use std::vec::Vec;

    struct Plain<'a>(&'a mut [u8]);

    impl Block for Plain<'_> {
        fn size(&self) -> usize {
            self.0.len()
        }
        fn byte(&self, i: usize) -> u8 {
            self.0[i]
        }
        fn correct(&mut self, i: usize, error: u8) {
            self.0[i] ^= error;
        }
    }

    fn encode(data: &[u8]) -> Vec<u8> {
        let mut v = data.to_vec();
        v.extend(parity(data.iter().copied()));
        v
    }

    #[test]
    fn field_tables_are_a_field() {
        assert_eq!(exp(0), 1);
        assert_eq!(exp(8), 0x1D); // α⁸ = x⁴ + x³ + x² + 1
        assert_eq!(exp(255), 1);
        for a in 1..=255u8 {
            assert_eq!(exp(log(a)), a);
            assert_eq!(mul(a, inv(a)), 1);
        }
        // The powers of α run through every non-zero byte once: α is primitive.
        let mut seen = [false; 256];
        for i in 0..255 {
            assert!(!seen[usize::from(exp(i))]);
            seen[usize::from(exp(i))] = true;
        }
    }

    #[test]
    fn the_generator_has_the_sixteen_roots_and_no_zero_coefficient() {
        let g = generator();
        assert!(g.iter().all(|&c| c != 0));
        for i in 0..PARITY {
            let x = exp(i);
            // g(x) = x¹⁶ + Σ g[j] x^(15−j)
            let v = g.iter().fold(1u8, |acc, &c| mul(acc, x) ^ c);
            assert_eq!(v, 0, "α^{i}");
        }
    }

    /// Parity computed independently with Python's `reedsolo` 1.7.0:
    /// `RSCodec(16).encode(bytes(range(1, 21)))[20:]` and `RSCodec(16).encode(b"123456789")[9:]`.
    #[test]
    fn the_table_parity_is_the_parity() {
        let mut x = 0x1234_5678u32;
        for len in [0usize, 1, 2, 17, 100, 239] {
            for _ in 0..20 {
                let data: Vec<u8> = (0..len)
                    .map(|_| {
                        x ^= x << 13;
                        x ^= x >> 17;
                        x ^= x << 5;
                        (x >> 24) as u8
                    })
                    .collect();
                assert_eq!(
                    parity_by_table(data.iter().copied()),
                    parity(data.iter().copied())
                );
            }
        }
    }

    #[test]
    fn parity_matches_reedsolo() {
        let data: Vec<u8> = (1..=20).collect();
        assert_eq!(
            parity(data.iter().copied()),
            [
                0x6d, 0xee, 0xa3, 0x83, 0x1c, 0xe1, 0xd2, 0x13, 0x2e, 0xdc, 0xde, 0x63, 0x8c, 0x1a,
                0xc2, 0x90
            ]
        );
        assert_eq!(
            parity(b"123456789".iter().copied()),
            [
                0x57, 0x55, 0xa7, 0x70, 0xf1, 0xf6, 0x9c, 0x34, 0x92, 0x0d, 0x63, 0x86, 0xa4, 0x19,
                0x1a, 0x96
            ]
        );
    }

    #[test]
    fn a_clean_block_is_left_alone() {
        let mut b = encode(b"hello, vehicle");
        assert_eq!(correct(&mut Plain(&mut b)), Ok(0));
        assert_eq!(&b[..14], b"hello, vehicle");
    }

    #[test]
    fn eight_errors_anywhere_are_corrected_nine_are_not() {
        let data: Vec<u8> = (0..239).map(|i| (i * 7 + 3) as u8).collect();
        let clean = encode(&data);
        let mut b = clean.clone();
        for k in 0..8 {
            b[k * 31] ^= 0x5A + k as u8;
        }
        assert_eq!(correct(&mut Plain(&mut b)), Ok(8));
        assert_eq!(b, clean);
        let mut b = clean.clone();
        for k in 0..9 {
            b[k * 27 + 1] ^= 0xC3;
        }
        let before = b.clone();
        // Nine errors: refused, or (rarely) a wrong codeword; never the original data claimed.
        match correct(&mut Plain(&mut b)) {
            Err(Uncorrectable) => assert_eq!(b, before),
            Ok(_) => assert_ne!(b, clean),
        }
    }

    #[test]
    fn too_short_or_too_long_blocks_are_refused() {
        let mut short = [0u8; PARITY];
        assert_eq!(correct(&mut Plain(&mut short)), Err(Uncorrectable));
        let mut long = [0u8; MAX_BLOCK + 1];
        assert_eq!(correct(&mut Plain(&mut long)), Err(Uncorrectable));
        // The shortest block: one data byte.
        let mut one = encode(&[0x42]);
        one[0] ^= 0xFF;
        one[5] ^= 1;
        assert_eq!(correct(&mut Plain(&mut one)), Ok(2));
        assert_eq!(one[0], 0x42);
    }

    proptest! {
        #![proptest_config(ProptestConfig { failure_persistence: None, ..ProptestConfig::default() })]

        /// Up to eight errors at any positions of a block of any length are corrected.
        #[test]
        fn up_to_eight_errors_are_corrected(
            data in proptest::collection::vec(any::<u8>(), 1..=MAX_DATA),
            errors in proptest::collection::vec((any::<usize>(), 1u8..=255), 0..=CORRECTABLE),
        ) {
            let clean = encode(&data);
            let mut b = clean.clone();
            let mut at = std::collections::BTreeSet::new();
            for (pos, e) in errors {
                let i = pos % b.len();
                if at.insert(i) {
                    b[i] ^= e;
                }
            }
            prop_assert_eq!(correct(&mut Plain(&mut b)), Ok(at.len()));
            prop_assert_eq!(b, clean);
        }

        /// Any bytes at all: never a panic, and what is claimed corrected is a codeword.
        #[test]
        fn arbitrary_blocks_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..300)) {
            let mut b = bytes.clone();
            if correct(&mut Plain(&mut b)).is_ok() {
                prop_assert_eq!(correct(&mut Plain(&mut b)), Ok(0));
            } else {
                prop_assert_eq!(b, bytes);
            }
        }
    }
}
