"""Number formats and orderings the report's sections share (make_report.py, captured_section.py)."""


def fmt_int(x):
    return "–" if x is None else f"{int(round(x)):,}"


def fmt_pct(x, digits=1):
    return "–" if x is None else f"{100 * x:.{digits}f} %"


def fmt_signed_pct(x):
    return "–" if x is None else f"{100 * x:+.1f} %"


def tile_key(t):
    """A tile size 'WxH' ordered by area, then width."""
    w, h = (int(v) for v in t.split("x"))
    return (w * h, w, h)
