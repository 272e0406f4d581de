"""C1 at 100 rpm on seed 003's 10B contact values (before the chains carried their own) and on
16B's (now), at levels 1 and 3: the figures quoted in docs/multibody.md "Parameters".

    python docs/scripts/c1_chain_values.py
"""

import chainmodel
from chainmodel.scene import load_scene

BEFORE = {"contact.stiffness": 8.46e6, "contact.damping": 74.0, "chain.breaking_load": 22.2e3}

for label, over in (("seed 003 10B contact (before)", BEFORE), ("16B contact (now)", {})):
    for level in (1, 3):
        sc = load_scene("C1", fidelity=level, input_speed_rpm=100, duration=2.0,
                        output_interval=2e-4, parameters=over)
        s = chainmodel.simulate(sc).summary()
        print(f"{label:30s} level {level}: k_c = {sc.parameters['contact.stiffness']:.4g} N/m, "
              f"mean tight {s['mean_tight_tension_n']:.1f} N, mean slack "
              f"{s['mean_slack_tension_n']:.1f} N, driven-speed ripple "
              f"{s['driven_speed_ripple_rms_rad_s']:.3f} rad/s RMS")
