//! Discovery's forms written as formulas: diagnosis.json names each form in plain ASCII
//! (`saturating: a = -v/(T0 + T'|v|)`); the page shows the formula part between dollar signs in
//! the TeX subset of `mathml` (MathML in report.html, `$…$` in report.md, as a forge renders
//! it). Absolute values are written `\lvert v\rvert`, so a formula in a Markdown table holds no
//! pipe. A form this file does not know is shown as written.

/// The ASCII formula of each form of discovery's library, and the same formula in TeX.
const FORMULAS: [(&str, &str); 16] = [
    ("a = -v/(T0 + T'|v|)", r"a = -v/(T_0 + T'\lvert v\rvert)"),
    ("a = -v/T - c v|v|", r"a = -v/T - c\,v\lvert v\rvert"),
    ("a = -c g sign(v)", r"a = -c\,g\,\text{sign}(v)"),
    ("a = -g sin(alpha)", r"a = -g\,\text{sin}\,\alpha"),
    (
        "a = A exp(-(z - z_c)^2 / (2 w^2))",
        r"a = A\,\text{exp}(-(z - z_c)^2/(2w^2))",
    ),
    (
        "a = A sin(2 pi z / lambda + phi)",
        r"a = A\,\text{sin}(2\pi z/\lambda + \phi)",
    ),
    (
        "a = A sin(2 pi f t + phi_run)",
        r"a = A\,\text{sin}(2\pi f t + \phi_{\text{run}})",
    ),
    (
        "mu(u) = mu_inf (1 - exp(-|u|/v_c))",
        r"\mu(u) = \mu_\infty(1 - \text{exp}(-\lvert u\rvert/v_c))",
    ),
    (
        "mu(u) = mu (1 + beta (|u|/u_ref - 1))",
        r"\mu(u) = \mu(1 + \beta(\lvert u\rvert/u_{\text{ref}} - 1))",
    ),
    (
        "mu(u) = mu (1 + delta exp(-|u|/v_s))",
        r"\mu(u) = \mu(1 + \delta\,\text{exp}(-\lvert u\rvert/v_s))",
    ),
    ("mu (1 + delta dir)", r"\mu(1 + \delta\,\text{dir})"),
    (
        "mu (1 + p1 P1(x) + p2 P2(x))",
        r"\mu(1 + p_1 P_1(x) + p_2 P_2(x))",
    ),
    (
        "mu (1 + A sin(2 pi z / lambda + phi))",
        r"\mu(1 + A\,\text{sin}(2\pi z/\lambda + \phi))",
    ),
    (
        "z_meas = z + a2 P2(x) + a3 P3(x)",
        r"z_{\text{meas}} = z + a_2 P_2(x) + a_3 P_3(x)",
    ),
    (
        "mu drifts with |v0|",
        r"$\mu$ drifts with $\lvert v_0\rvert$",
    ),
    ("T drifts with |v0|", r"$T$ drifts with $\lvert v_0\rvert$"),
];

/// `form` with its formula between dollar signs, when it is one this file knows.
pub fn form(form: &str) -> String {
    for (ascii, tex) in FORMULAS {
        if let Some(i) = form.find(ascii) {
            // a probe's words carry their own dollar signs
            let tex = if tex.contains('$') {
                tex.to_string()
            } else {
                format!("${tex}$")
            };
            return format!("{}{tex}{}", &form[..i], &form[i + ascii.len()..]);
        }
    }
    form.to_string()
}

/// The drag law T(|v|) = T0 + T'|v| as a formula.
pub const DRAG_LINE: &str = r"$T(\lvert v\rvert) = T_0 + T'\lvert v\rvert$";

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn known_forms_become_formulas_and_others_stay() {
        assert_eq!(
            form("saturating: a = -v/(T0 + T'|v|)"),
            r"saturating: $a = -v/(T_0 + T'\lvert v\rvert)$"
        );
        assert_eq!(
            form("periodic in z: a = A sin(2 pi z / lambda + phi), fixed in the lab"),
            r"periodic in z: $a = A\,\text{sin}(2\pi z/\lambda + \phi)$, fixed in the lab"
        );
        assert_eq!(
            form("periodic mu(z) along the groove: mu (1 + A sin(2 pi z / lambda + phi)), fixed in the lab"),
            r"periodic mu(z) along the groove: $\mu(1 + A\,\text{sin}(2\pi z/\lambda + \phi))$, fixed in the lab"
        );
        assert_eq!(
            form("probe: T drifts with |v0|"),
            r"probe: $T$ drifts with $\lvert v_0\rvert$"
        );
        assert_eq!(form("something new"), "something new");
        // no pipe is left for a Markdown table to split on
        for (_, tex) in FORMULAS {
            assert!(!tex.contains('|'), "{tex}");
        }
        let html = crate::report::mathml::inline(r"a = -v/(T_0 + T'\lvert v\rvert)");
        assert!(
            html.contains("<msub><mi>T</mi><mn>0</mn></msub>")
                && html.contains("<mo lspace=\"0\" rspace=\"0\">|</mo><mi>v</mi>"),
            "{html}"
        );
        assert!(!html.contains("mtext>\\"), "{html}");
    }
}
