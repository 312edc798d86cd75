//! SVG text without a plotting crate: XML escaping, number formatting and a
//! small writer of the elements the charts use (line, polyline, circle,
//! text, group), plus the chart frame (title, axes with tick labels, legend)
//! shared by the aperture and meter charts.

use std::fmt::Write;

use chrono::NaiveDate;

use super::scale::{day_number, month_ticks, nice_ticks, tick_decimals, Scale};

/// Escapes text for XML content and attribute values.
pub fn escape(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&apos;"),
            _ => out.push(c),
        }
    }
    out
}

/// A pixel coordinate: one decimal is finer than any screen needs and keeps
/// the files small.
pub fn px(v: f64) -> String {
    format!("{v:.1}")
}

/// A data value with at most `decimals` decimals, trailing zeros dropped
/// ("0.5", not "0.500").
pub fn num(v: f64, decimals: usize) -> String {
    let s = format!("{v:.decimals$}");
    let s = if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    };
    if s == "-0" {
        "0".into()
    } else {
        s
    }
}

/// An SVG document under construction.
pub struct Svg {
    body: String,
    width: f64,
    height: f64,
}

impl Svg {
    pub fn new(width: f64, height: f64) -> Svg {
        Svg {
            body: String::new(),
            width,
            height,
        }
    }

    /// `<line>`; `class` also selects the style in the document's `<style>`.
    pub fn line(&mut self, class: &str, a: (f64, f64), b: (f64, f64)) {
        let _ = writeln!(
            self.body,
            r#"<line class="{}" x1="{}" y1="{}" x2="{}" y2="{}"/>"#,
            escape(class),
            px(a.0),
            px(a.1),
            px(b.0),
            px(b.1)
        );
    }

    pub fn polyline(&mut self, class: &str, points: &[(f64, f64)]) {
        let pts: Vec<String> = points
            .iter()
            .map(|p| format!("{},{}", px(p.0), px(p.1)))
            .collect();
        let _ = writeln!(
            self.body,
            r#"<polyline class="{}" points="{}"/>"#,
            escape(class),
            pts.join(" ")
        );
    }

    pub fn circle(&mut self, class: &str, c: (f64, f64), r: f64) {
        let _ = writeln!(
            self.body,
            r#"<circle class="{}" cx="{}" cy="{}" r="{}"/>"#,
            escape(class),
            px(c.0),
            px(c.1),
            px(r)
        );
    }

    /// `anchor`: start, middle or end.
    pub fn text(&mut self, class: &str, at: (f64, f64), anchor: &str, text: &str) {
        let _ = writeln!(
            self.body,
            r#"<text class="{}" x="{}" y="{}" text-anchor="{}">{}</text>"#,
            escape(class),
            px(at.0),
            px(at.1),
            anchor,
            escape(text)
        );
    }

    /// Text turned a quarter anticlockwise about its anchor, for a y-axis title.
    pub fn vertical_text(&mut self, class: &str, at: (f64, f64), text: &str) {
        let _ = writeln!(
            self.body,
            r#"<text class="{}" x="{x}" y="{y}" text-anchor="middle" transform="rotate(-90 {x} {y})">{}</text>"#,
            escape(class),
            escape(text),
            x = px(at.0),
            y = px(at.1),
        );
    }

    pub fn open_group(&mut self, class: &str) {
        let _ = writeln!(self.body, r#"<g class="{}">"#, escape(class));
    }

    pub fn close_group(&mut self) {
        self.body.push_str("</g>\n");
    }

    /// The document; `style` is CSS for the classes used.
    pub fn finish(self, title: &str, style: &str) -> String {
        format!(
            concat!(
                r#"<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" viewBox="0 0 {w} {h}" font-family="sans-serif" font-size="12">"#,
                "\n<title>{t}</title>\n<style>{s}</style>\n",
                r#"<rect class="background" x="0" y="0" width="{w}" height="{h}" fill="white"/>"#,
                "\n{b}</svg>\n"
            ),
            w = px(self.width),
            h = px(self.height),
            t = escape(title),
            s = style,
            b = self.body
        )
    }
}

/// Pixel box of the plotting area inside the chart.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Frame {
    pub left: f64,
    pub top: f64,
    pub right: f64,
    pub bottom: f64,
}

/// Size and margins of every chart; the margins leave room for tick labels,
/// the title above and the legend below.
pub const WIDTH: f64 = 720.0;
pub const HEIGHT: f64 = 400.0;
pub const FRAME: Frame = Frame {
    left: 60.0,
    top: 40.0,
    right: WIDTH - 20.0,
    bottom: HEIGHT - 70.0,
};

/// The plotting area of a zone chart's temperature panel, under the
/// aperture panel (`FRAME`) in a chart `ZONE_HEIGHT` high.
pub const TEMPERATURE_FRAME: Frame = Frame {
    left: FRAME.left,
    top: FRAME.bottom + 50.0,
    right: FRAME.right,
    bottom: FRAME.bottom + 230.0,
};
pub const ZONE_HEIGHT: f64 = TEMPERATURE_FRAME.bottom + 100.0;

/// Date axis × value axis (mm, or °C on a temperature panel) of a chart in
/// one frame, with the ticks drawn.
#[derive(Debug, Clone, PartialEq)]
pub struct DateMmAxes {
    pub x: Scale,
    pub y: Scale,
    pub date_ticks: Vec<NaiveDate>,
    /// value ticks, in the unit of the y axis
    pub mm_ticks: Vec<f64>,
    pub frame: Frame,
    pub y_title: String,
}

impl DateMmAxes {
    /// Aperture axes in `FRAME` spanning the dates `[d0, d1]` and the values
    /// `[lo, hi]` mm, widened to round ticks (and always including 0 mm, so
    /// apertures are seen against a closed joint).
    pub fn new(d0: NaiveDate, d1: NaiveDate, lo: f64, hi: f64) -> DateMmAxes {
        DateMmAxes::in_frame(FRAME, d0, d1, (lo.min(0.0), hi), "aperture [mm]")
    }

    /// Axes in `frame` spanning `[d0, d1]` and the values `[lo, hi]`,
    /// widened to round ticks; `y_title` names the quantity and unit.
    pub fn in_frame(
        frame: Frame,
        d0: NaiveDate,
        d1: NaiveDate,
        (lo, hi): (f64, f64),
        y_title: &str,
    ) -> DateMmAxes {
        let hi = if hi > lo { hi } else { lo + 1.0 };
        let mm_ticks = nice_ticks(lo, hi, 5);
        let y = Scale::new(
            (mm_ticks[0], *mm_ticks.last().expect("at least one tick")),
            (frame.bottom, frame.top),
        );
        let x = Scale::new((day_number(d0), day_number(d1)), (frame.left, frame.right));
        DateMmAxes {
            x,
            y,
            date_ticks: month_ticks(d0, d1, 8),
            mm_ticks,
            frame,
            y_title: y_title.to_string(),
        }
    }

    pub fn xd(&self, d: NaiveDate) -> f64 {
        self.x.map(day_number(d))
    }

    pub fn ymm(&self, mm: f64) -> f64 {
        self.y.map(mm)
    }

    /// Grid, axes, tick labels and the y-axis title.
    pub fn draw(&self, svg: &mut Svg) {
        let f = self.frame;
        svg.open_group("grid");
        for &t in &self.mm_ticks {
            let y = self.ymm(t);
            svg.line("grid", (f.left, y), (f.right, y));
        }
        for &d in &self.date_ticks {
            let x = self.xd(d);
            svg.line("grid", (x, f.top), (x, f.bottom));
        }
        svg.close_group();
        svg.open_group("axes");
        svg.line("axis", (f.left, f.bottom), (f.right, f.bottom));
        svg.line("axis", (f.left, f.top), (f.left, f.bottom));
        let decimals = match self.mm_ticks.as_slice() {
            [a, b, ..] => tick_decimals(b - a),
            _ => 1,
        };
        for &t in &self.mm_ticks {
            let y = self.ymm(t);
            svg.line("tick", (f.left - 4.0, y), (f.left, y));
            svg.text(
                "tick-label",
                (f.left - 6.0, y + 4.0),
                "end",
                &num(t, decimals),
            );
        }
        for &d in &self.date_ticks {
            let x = self.xd(d);
            svg.line("tick", (x, f.bottom), (x, f.bottom + 4.0));
            svg.text(
                "tick-label",
                (x, f.bottom + 16.0),
                "middle",
                &d.format("%b %Y").to_string(),
            );
        }
        svg.vertical_text(
            "axis-title",
            (16.0, (f.top + f.bottom) / 2.0),
            &self.y_title,
        );
        svg.close_group();
    }
}

/// Legend entries in rows below the axes of `frame`: (class of the sample,
/// label, marker instead of a line); a row that would pass the frame's right
/// edge wraps.
pub fn legend(svg: &mut Svg, frame: Frame, entries: &[(&str, &str, bool)]) {
    let mut y = frame.bottom + 40.0;
    let mut x = frame.left;
    svg.open_group("legend");
    for &(class, label, marker) in entries {
        // Labels are short; 7 px per character is a safe estimate at 12 px.
        let w = 40.0 + 7.0 * label.chars().count() as f64;
        if x > frame.left && x + w - 14.0 > frame.right {
            (x, y) = (frame.left, y + 16.0);
        }
        if marker {
            svg.circle(class, (x + 10.0, y - 4.0), 3.5);
        } else {
            svg.line(class, (x, y - 4.0), (x + 20.0, y - 4.0));
        }
        svg.text("legend-label", (x + 26.0, y), "start", label);
        x += w;
    }
    svg.close_group();
}

/// Chart title centred above the frame.
pub fn title(svg: &mut Svg, text: &str) {
    svg.text("title", (WIDTH / 2.0, 24.0), "middle", text);
}

/// Style shared by the charts: series colours and the dashed limit line.
pub const STYLE: &str = concat!(
    ".grid{stroke:#e4e4e4;stroke-width:1}",
    ".axis,.tick{stroke:#333;stroke-width:1}",
    ".title{font-size:15px;font-weight:bold}",
    ".tick-label,.legend-label{fill:#333}",
    ".axis-title{fill:#333}",
    ".upstream{stroke:#1f77b4;fill:none;stroke-width:1.8}",
    ".center{stroke:#2ca02c;fill:none;stroke-width:1.8}",
    ".downstream{stroke:#ff7f0e;fill:none;stroke-width:1.8}",
    ".min{stroke:#000;fill:none;stroke-width:2.6}",
    ".remedy{stroke:#9467bd;fill:none;stroke-width:2.6;stroke-dasharray:8 4}",
    ".remedy-date{stroke:#9467bd;stroke-width:1.2;stroke-dasharray:2 3}",
    ".temperature{stroke:#8c564b;fill:none;stroke-width:2}",
    ".remedy-temperature{stroke:#9467bd;fill:none;stroke-width:2;stroke-dasharray:8 4}",
    ".closure{stroke:#17becf;stroke-width:1.2;stroke-dasharray:2 3}",
    ".temperature-limit{stroke:#d62728;stroke-width:1.2;stroke-dasharray:6 4}",
    ".subtitle{fill:#333}",
    ".predicted{stroke:#1f77b4;fill:none;stroke-width:1.8}",
    ".measured{fill:#d62728;stroke:none}",
    ".limit{stroke:#d62728;stroke-width:1.2;stroke-dasharray:6 4}",
    ".limit-label{fill:#d62728}",
    ".planned{stroke:#555;stroke-width:1.2;stroke-dasharray:2 3}",
    ".planned-label{fill:#555}",
);

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn escapes_markup() {
        assert_eq!(
            escape(r#"a<b & "c">'"#),
            "a&lt;b &amp; &quot;c&quot;&gt;&apos;"
        );
    }

    #[test]
    fn numbers_trim_trailing_zeros() {
        assert_eq!(num(0.5, 3), "0.5");
        assert_eq!(num(2.0, 2), "2");
        assert_eq!(num(-0.0001, 2), "0");
        assert_eq!(num(1.256, 2), "1.26");
        assert_eq!(px(12.345), "12.3");
    }

    #[test]
    fn document_is_closed() {
        let mut s = Svg::new(10.0, 10.0);
        s.open_group("g");
        s.text("t", (1.0, 2.0), "start", "x < y");
        s.close_group();
        let doc = s.finish("T & U", "");
        assert!(doc.starts_with("<svg "));
        assert!(doc.trim_end().ends_with("</svg>"));
        assert!(doc.contains("<title>T &amp; U</title>"));
        assert!(doc.contains(">x &lt; y</text>"));
    }
}
