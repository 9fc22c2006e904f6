"""Speed-controlled motor FMU (pythonfmu; built by drivetrain.py): PI control of
the measured shaft speed to a ramped set-point, torque out.

Set-point: w_ref(t) = speed_full * min(1, t/ramp_time) (rad/s).  Control law
(textbook PI with clamping anti-windup): T = clamp(kp*(w_ref - w) + I, 0,
torque_max), dI/dt = ki*(w_ref - w) while T is not saturated.  Forward Euler over
the communication step with the measured speed held (a co-simulation input).
"""
from pythonfmu import Fmi2Causality, Fmi2Slave, Fmi2Variability, Real


class SpeedMotor(Fmi2Slave):
    author = "gearfmu example"
    description = "PI speed-controlled motor: speed in, torque out"

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.speed = 0.0          # rad/s, measured shaft speed (input)
        self.torque = 0.0         # N*m (output)
        self.speed_full = 209.43951023931953  # rad/s
        self.ramp_time = 0.4      # s
        self.kp = 40.0            # N*m/(rad/s)
        self.ki = 800.0           # N*m/rad
        self.torque_max = 4000.0  # N*m
        self.speed_ref = 0.0      # rad/s (output, for plots)
        self._integral = 0.0
        self.register_variable(Real("speed", causality=Fmi2Causality.input))
        self.register_variable(Real("torque", causality=Fmi2Causality.output))
        self.register_variable(Real("speed_ref", causality=Fmi2Causality.output))
        for name in ("speed_full", "ramp_time", "kp", "ki", "torque_max"):
            self.register_variable(Real(name, causality=Fmi2Causality.parameter, variability=Fmi2Variability.tunable))

    def _ref(self, t):
        return self.speed_full * min(1.0, t / self.ramp_time) if self.ramp_time > 0 else self.speed_full

    def do_step(self, current_time, step_size):
        t = current_time + step_size
        err = self._ref(current_time) - self.speed
        raw = self.kp * err + self._integral
        if 0.0 < raw < self.torque_max or (raw <= 0.0 and err > 0) or (raw >= self.torque_max and err < 0):
            self._integral += self.ki * err * step_size
        self.speed_ref = self._ref(t)
        err = self.speed_ref - self.speed
        self.torque = min(max(self.kp * err + self._integral, 0.0), self.torque_max)
        return True
