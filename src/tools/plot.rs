//! A small log-log line plot as standalone SVG (decade grid, one coloured line with markers per
//! series, a legend), for `photonmap converge --plot`. Hand-written: plotters' text layout needs
//! system fonts, and this needs none.

use std::fmt::Write as _;

/// A named line of `(x, y)` points, both positive.
pub struct Series {
    pub name: String,
    pub points: Vec<(f64, f64)>,
    /// Drawn dashed with hollow markers (for figures measured elsewhere, such as other
    /// renderers').
    pub dashed: bool,
}

const W: f64 = 720.0;
const H: f64 = 480.0;
const LEFT: f64 = 70.0;
const RIGHT: f64 = 230.0;
const TOP: f64 = 40.0;
const BOTTOM: f64 = 55.0;
const COLORS: [&str; 8] =
    ["#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#8c564b", "#e377c2", "#17becf"];

/// Decades `[lo, hi]` (powers of ten) covering `values`, at least one decade wide.
fn decades(values: impl Iterator<Item = f64>) -> (i32, i32) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in values.filter(|v| v.is_finite() && *v > 0.0) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if !lo.is_finite() {
        return (0, 1);
    }
    let (a, b) = (lo.log10().floor() as i32, hi.log10().ceil() as i32);
    (a, b.max(a + 1))
}

fn escape(s: &str) -> String {
    s.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;")
}

fn tick_label(exp: i32) -> String {
    let v = 10f64.powi(exp);
    if (-3..=4).contains(&exp) {
        format!("{}", v)
    } else {
        format!("1e{exp}")
    }
}

/// The plot as an SVG document.
pub fn log_log_svg(title: &str, x_label: &str, y_label: &str, series: &[Series]) -> String {
    let all = || series.iter().flat_map(|s| s.points.iter());
    let (x0, x1) = decades(all().map(|p| p.0));
    let (y0, y1) = decades(all().map(|p| p.1));
    let (pw, ph) = (W - LEFT - RIGHT, H - TOP - BOTTOM);
    let sx = |x: f64| LEFT + (x.log10() - x0 as f64) / (x1 - x0) as f64 * pw;
    let sy = |y: f64| TOP + ph - (y.log10() - y0 as f64) / (y1 - y0) as f64 * ph;
    let mut s = String::new();
    let _ = writeln!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{W}" height="{H}" viewBox="0 0 {W} {H}" font-family="sans-serif" font-size="12">"#
    );
    let _ = writeln!(s, r#"<rect width="{W}" height="{H}" fill="white"/>"#);
    let _ = writeln!(
        s,
        r#"<text x="{}" y="22" text-anchor="middle" font-size="15">{}</text>"#,
        LEFT + pw / 2.0,
        escape(title)
    );
    // Grid: decades solid, 2..9 within them faint.
    for e in x0..=x1 {
        for m in 1..10 {
            let x = m as f64 * 10f64.powi(e);
            if e == x1 && m > 1 {
                break;
            }
            let (px, stroke) = (sx(x), if m == 1 { "#bbb" } else { "#eee" });
            let _ = writeln!(
                s,
                r#"<line x1="{px:.1}" y1="{TOP}" x2="{px:.1}" y2="{}" stroke="{stroke}"/>"#,
                TOP + ph
            );
        }
        let _ = writeln!(
            s,
            r#"<text x="{:.1}" y="{}" text-anchor="middle">{}</text>"#,
            sx(10f64.powi(e)),
            TOP + ph + 18.0,
            tick_label(e)
        );
    }
    for e in y0..=y1 {
        for m in 1..10 {
            let y = m as f64 * 10f64.powi(e);
            if e == y1 && m > 1 {
                break;
            }
            let (py, stroke) = (sy(y), if m == 1 { "#bbb" } else { "#eee" });
            let _ = writeln!(
                s,
                r#"<line x1="{LEFT}" y1="{py:.1}" x2="{}" y2="{py:.1}" stroke="{stroke}"/>"#,
                LEFT + pw
            );
        }
        let _ = writeln!(
            s,
            r#"<text x="{}" y="{:.1}" text-anchor="end" dominant-baseline="middle">{}</text>"#,
            LEFT - 6.0,
            sy(10f64.powi(e)),
            tick_label(e)
        );
    }
    let _ =
        writeln!(s, r#"<rect x="{LEFT}" y="{TOP}" width="{pw}" height="{ph}" fill="none" stroke="black"/>"#);
    let _ = writeln!(
        s,
        r#"<text x="{}" y="{}" text-anchor="middle">{}</text>"#,
        LEFT + pw / 2.0,
        H - 12.0,
        escape(x_label)
    );
    let _ = writeln!(
        s,
        r#"<text transform="translate(18 {}) rotate(-90)" text-anchor="middle">{}</text>"#,
        TOP + ph / 2.0,
        escape(y_label)
    );
    for (i, ser) in series.iter().enumerate() {
        let color = COLORS[i % COLORS.len()];
        let mut pts: Vec<(f64, f64)> = ser
            .points
            .iter()
            .copied()
            .filter(|&(x, y)| x > 0.0 && y > 0.0 && x.is_finite() && y.is_finite())
            .collect();
        pts.sort_by(|a, b| a.0.total_cmp(&b.0));
        let path: Vec<String> = pts.iter().map(|&(x, y)| format!("{:.1},{:.1}", sx(x), sy(y))).collect();
        let dash = if ser.dashed { r#" stroke-dasharray="6 4""# } else { "" };
        let _ = writeln!(
            s,
            r#"<polyline points="{}" fill="none" stroke="{color}" stroke-width="2"{dash}/>"#,
            path.join(" ")
        );
        let fill = if ser.dashed {
            format!(r#"fill="white" stroke="{color}" stroke-width="1.5""#)
        } else {
            format!(r#"fill="{color}""#)
        };
        for &(x, y) in &pts {
            let _ = writeln!(s, r#"<circle cx="{:.1}" cy="{:.1}" r="3.5" {fill}/>"#, sx(x), sy(y));
        }
        let ly = TOP + 10.0 + 20.0 * i as f64;
        let lx = LEFT + pw + 15.0;
        let _ = writeln!(
            s,
            r#"<line x1="{lx}" y1="{ly}" x2="{}" y2="{ly}" stroke="{color}" stroke-width="2"{dash}/><text x="{}" y="{ly}" dominant-baseline="middle">{}</text>"#,
            lx + 22.0,
            lx + 28.0,
            escape(&ser.name)
        );
    }
    s.push_str("</svg>\n");
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn decades_cover_the_values() {
        assert_eq!(decades([0.012, 0.3].into_iter()), (-2, 0));
        assert_eq!(decades([1.0].into_iter()), (0, 1));
        assert_eq!(decades(std::iter::empty()), (0, 1));
    }

    #[test]
    fn points_land_inside_the_frame() {
        let series = vec![
            Series { name: "a<b".into(), points: vec![(1.0, 0.1), (30.0, 0.01)], dashed: false },
            Series { name: "peer".into(), points: vec![(5.0, 0.05)], dashed: true },
        ];
        let svg = log_log_svg("t", "x", "y", &series);
        assert!(svg.contains("a&lt;b"));
        assert_eq!(svg.matches("stroke-dasharray").count(), 2, "the peer's line and legend are dashed");
        for c in svg.split("<circle").skip(1) {
            let cx: f64 = c.split("cx=\"").nth(1).unwrap().split('"').next().unwrap().parse().unwrap();
            let cy: f64 = c.split("cy=\"").nth(1).unwrap().split('"').next().unwrap().parse().unwrap();
            assert!((LEFT..=W - RIGHT).contains(&cx) && (TOP..=H - BOTTOM).contains(&cy), "{cx} {cy}");
        }
    }
}
