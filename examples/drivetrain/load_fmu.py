"""Load FMU (pythonfmu; built by drivetrain.py): a load inertia with drag behind
a torsional shaft (spring-damper) -- the standard way to couple two inertias
in co-simulation: the gear FMU sends its gear angle and speed, this FMU
returns the shaft torque that loads the gear.

J_L dw_L/dt = T_s - c1*w_L - c2*w_L*|w_L| - T_step(t),
T_s = k_s*(theta_g - theta_L) + c_s*(w_g - w_L),
T_step = step_torque for t >= step_time.  Integrated with classical RK4 over
n_sub substeps of each communication step, gear angle/speed extrapolated
linearly over the step (theta_g + w_g*tau).
"""
from pythonfmu import Fmi2Causality, Fmi2Slave, Fmi2Variability, Real


class LoadInertia(Fmi2Slave):
    author = "gearfmu example"
    description = "Load inertia with linear and quadratic drag behind a torsional shaft"

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.shaft_angle = 0.0    # rad, gear-side shaft angle (input)
        self.shaft_speed = 0.0    # rad/s (input)
        self.shaft_torque = 0.0   # N*m (output: load torque on the gear, positive resists)
        self.load_speed = 0.0     # rad/s (output)
        self.J = 0.5              # kg*m^2
        self.k_s = 5.0e4          # N*m/rad
        self.c_s = 40.0           # N*m*s/rad
        self.c1 = 0.5             # N*m*s/rad
        self.c2 = 0.012           # N*m*s^2/rad^2
        self.step_time = 0.6      # s
        self.step_torque = 600.0  # N*m
        self.n_sub = 10
        self._th = 0.0
        self._w = 0.0
        self.register_variable(Real("shaft_angle", causality=Fmi2Causality.input))
        self.register_variable(Real("shaft_speed", causality=Fmi2Causality.input))
        self.register_variable(Real("shaft_torque", causality=Fmi2Causality.output))
        self.register_variable(Real("load_speed", causality=Fmi2Causality.output))
        for name in ("J", "k_s", "c_s", "c1", "c2", "step_time", "step_torque"):
            self.register_variable(Real(name, causality=Fmi2Causality.parameter, variability=Fmi2Variability.tunable))

    def _f(self, tau, th, w, t0):
        thg = self.shaft_angle + self.shaft_speed * tau
        ts = self.k_s * (thg - th) + self.c_s * (self.shaft_speed - w)
        tl = self.c1 * w + self.c2 * w * abs(w) + (self.step_torque if t0 + tau >= self.step_time else 0.0)
        return w, (ts - tl) / self.J

    def do_step(self, current_time, step_size):
        h = step_size / self.n_sub
        th, w = self._th, self._w
        # the shaft starts relaxed at the gear's angle
        if current_time == 0.0 and th == 0.0 and w == 0.0:
            th = self.shaft_angle
        for i in range(self.n_sub):
            tau = i * h
            a1, b1 = self._f(tau, th, w, current_time)
            a2, b2 = self._f(tau + h / 2, th + h / 2 * a1, w + h / 2 * b1, current_time)
            a3, b3 = self._f(tau + h / 2, th + h / 2 * a2, w + h / 2 * b2, current_time)
            a4, b4 = self._f(tau + h, th + h * a3, w + h * b3, current_time)
            th += h / 6 * (a1 + 2 * a2 + 2 * a3 + a4)
            w += h / 6 * (b1 + 2 * b2 + 2 * b3 + b4)
        self._th, self._w = th, w
        thg = self.shaft_angle + self.shaft_speed * step_size
        self.shaft_torque = self.k_s * (thg - th) + self.c_s * (self.shaft_speed - w)
        self.load_speed = w
        return True
