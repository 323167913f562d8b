//! Sums over square windows of an image's pixels in constant time each: a summed-area table
//! of `N` values a pixel. The bias correction of pass-indexed progressive photon mapping
//! ([`super::sums`]) and the pilot's pooling of its measurements (`integrator::bandwidth`)
//! both average over a window about each pixel.

/// The summed-area table of a `width`-wide image's `N` values a pixel.
pub struct Windows<const N: usize> {
    width: usize,
    height: usize,
    /// `(width + 1) × (height + 1)` running sums, a row and a column of zeros first.
    table: Vec<[f64; N]>,
}

impl<const N: usize> Windows<N> {
    /// The table of `value(x, y)` over the pixels of a `width × height` image, row by row.
    pub fn new(width: usize, height: usize, mut value: impl FnMut(usize, usize) -> [f64; N]) -> Self {
        let w1 = width + 1;
        let mut table = vec![[0f64; N]; w1 * (height + 1)];
        for y in 0..height {
            let mut row = [0f64; N];
            for x in 0..width {
                for (sum, v) in row.iter_mut().zip(value(x, y)) {
                    *sum += v;
                }
                let above = table[y * w1 + x + 1];
                table[(y + 1) * w1 + x + 1] = std::array::from_fn(|i| above[i] + row[i]);
            }
        }
        Windows { width, height, table }
    }

    /// The sums over the window reaching `reach` pixels each way from `(x, y)`, cut by the
    /// image's border, and how many pixels it holds.
    pub fn around(&self, x: usize, y: usize, reach: usize) -> ([f64; N], usize) {
        let (x0, x1) = (x.saturating_sub(reach), (x + reach + 1).min(self.width));
        let (y0, y1) = (y.saturating_sub(reach), (y + reach + 1).min(self.height));
        let w1 = self.width + 1;
        let at = |x: usize, y: usize| self.table[y * w1 + x];
        let (a, b, c, d) = (at(x1, y1), at(x0, y1), at(x1, y0), at(x0, y0));
        (std::array::from_fn(|i| a[i] - b[i] - c[i] + d[i]), (x1 - x0) * (y1 - y0))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn window_sums_match_the_pixels_they_hold() {
        let (w, h) = (7, 5);
        let value = |x: usize, y: usize| [(x * 10 + y) as f64, 1.0];
        let windows = Windows::new(w, h, value);
        for (x, y, reach) in [(0, 0, 1), (3, 2, 1), (6, 4, 2), (3, 2, 10), (2, 3, 0)] {
            let (sums, count) = windows.around(x, y, reach);
            let (mut expect, mut n) = (0.0, 0);
            for yy in y.saturating_sub(reach)..(y + reach + 1).min(h) {
                for xx in x.saturating_sub(reach)..(x + reach + 1).min(w) {
                    expect += value(xx, yy)[0];
                    n += 1;
                }
            }
            assert_eq!((sums[0], sums[1] as usize, count), (expect, n, n), "({x}, {y}) reach {reach}");
        }
    }
}
