"""Driven-speed ripple and spectrum peaks of every level on xu2010 (docs/reduced_models.md).
Run: python docs/scripts/spectra.py"""
import numpy as np

import chainmodel


def report(tag, **kw):
    r = chainmodel.simulate("xu2010", duration=1.0, output_interval=1e-4, **kw)
    m = r.time >= 0.5
    w = r["driven.speed"][m]
    spec = np.abs(np.fft.rfft((w - w.mean()) * np.hanning(w.size)))
    f = np.fft.rfftfreq(w.size, 1e-4)
    band = (f > 500) & (f < 700)
    print(f"{tag:40s} ripple {np.std(w):.3f} rad/s  50 Hz {spec[np.argmin(abs(f - 50))]:6.0f}  "
          f"500-700 Hz {spec[band].max():6.0f}  mean tight {r['tight_span.tension'][m].mean():7.1f} N")


if __name__ == "__main__":
    report("level 3 multibody", fidelity=3)
    report("level 1, mean-count compliance", fidelity=1)
    report("level 1, current-count compliance", fidelity=1, torsional_mean_link_compliance=False)
    report("level 2, mean-count compliance", fidelity=2)
