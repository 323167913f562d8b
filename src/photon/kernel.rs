//! Density-estimation kernels over a gather disc (Jensen 2001, 7.2.1): the weight of a photon
//! at a given distance, and the weight within part of the disc, for estimates over a footprint.

use crate::config::Kernel;

/// Kernel weight at squared normalised distance `t2 = d^2 / r^2`, normalised so that the
/// weights integrate to 1 over the disc of area `pi r^2` (Jensen 2001, 7.2.1): box 1; cone
/// `(1 - d/r) / (1 - 2/3)`; Gaussian (Pavicic 1990) `a (1 - (1 - e^(-b t2/2)) / (1 - e^-b))`
/// with `a = 0.918`, `b = 1.953`, divided by its mean over the disc,
/// `a (1 - (1 - (2/b)(1 - e^(-b/2))) / (1 - e^-b)) = 0.53115` (Jensen's constants alone give
/// the shape, not unit integral: used as printed they darken the estimate by 47 %).
#[inline]
pub fn kernel_weight(kernel: Kernel, t2: f32) -> f32 {
    match kernel {
        Kernel::Box => 1.0,
        Kernel::Cone => 3.0 * (1.0 - t2.sqrt()).max(0.0),
        Kernel::Gaussian => {
            const A: f32 = 0.918;
            const B: f32 = 1.953;
            const MEAN: f32 = 0.531_154_9;
            (A / MEAN) * (1.0 - (1.0 - (-B * 0.5 * t2).exp()) / (1.0 - (-B).exp()))
        }
    }
}

/// The kernel's weight within the disc of radius `t r` (`t` in `[0, 1]`) over its weight in
/// the whole disc of radius `r`: `2 ∫₀ᵗ kernel_weight(s²) s ds` (box `t²`, cone `3t² − 2t³`,
/// Gaussian in closed form), for estimates over part of a disc ([`super::footprint`]).
#[inline]
pub fn kernel_integral(kernel: Kernel, t: f32) -> f32 {
    let t2 = t * t;
    match kernel {
        Kernel::Box => t2,
        Kernel::Cone => t2 * (3.0 - 2.0 * t),
        Kernel::Gaussian => {
            const A: f32 = 0.918;
            const B: f32 = 1.953;
            const MEAN: f32 = 0.531_154_9;
            let c = 1.0 / (1.0 - (-B).exp());
            (A / MEAN) * ((1.0 - c) * t2 + c * (2.0 / B) * (1.0 - (-B * 0.5 * t2).exp()))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Integrates a kernel over the unit disc numerically: must be 1 (times pi r^2 = pi).
    #[test]
    fn kernels_are_normalised() {
        for kernel in [Kernel::Box, Kernel::Cone, Kernel::Gaussian] {
            let n = 20000;
            let mut integral = 0.0f64;
            for i in 0..n {
                let r = (i as f64 + 0.5) / n as f64;
                integral +=
                    kernel_weight(kernel, (r * r) as f32) as f64 * 2.0 * std::f64::consts::PI * r / n as f64;
            }
            let expect = std::f64::consts::PI;
            assert!((integral - expect).abs() / expect < 0.01, "{kernel:?}: {integral}");
        }
    }

    /// `kernel_integral` is the weight's integral out to `t r`, over the whole disc's.
    #[test]
    fn kernel_integrals_are_the_weights_integrals() {
        for kernel in [Kernel::Box, Kernel::Cone, Kernel::Gaussian] {
            for t in [0.0f64, 0.1, 0.35, 0.5, 0.8, 1.0] {
                let n = 20000;
                let integral: f64 = (0..n)
                    .map(|i| {
                        let s = t * (i as f64 + 0.5) / n as f64;
                        2.0 * kernel_weight(kernel, (s * s) as f32) as f64 * s * t / n as f64
                    })
                    .sum();
                let got = kernel_integral(kernel, t as f32) as f64;
                assert!((got - integral).abs() < 1e-3, "{kernel:?} at {t}: {got} against {integral}");
            }
        }
    }
}
