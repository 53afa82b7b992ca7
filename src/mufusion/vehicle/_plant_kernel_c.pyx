# cython: language_level=3, boundscheck=False, wraparound=False, cdivision=True
"""Compiled twin of :class:`mufusion.vehicle.plant_kernel.PlantKernel` (same results, bit for bit).

Every expression is the Python kernel's, in its operand order, on C doubles: IEEE-754 double
arithmetic rounds each operation exactly as CPython's float does, and ``sin``, ``cos``, ``atan``
come from the same C library ``math`` calls. The build turns off floating-point contraction
(``-ffp-contract=off``: no fused multiply-adds) and never enables fast-math, so nothing is
reassociated. ``cdivision`` drops Python's ZeroDivisionError check; the Python kernel never
divides by zero (every denominator is floored or a vehicle constant), and the tests compare
both kernels on whole runs, wheel lock-ups and friction changes included.

``b if b > a else a`` stands for Python's ``max(a, b)`` as in the Python kernel (the same value,
NaN and signed zeros included).
"""

from libc.math cimport atan, cos, fabs, sin, sqrt

cdef double SMALL_SLIP_SQUARED = 1e-12 * 1e-12

cdef struct Tire:
    double kx
    double ky
    double shape_x
    double shape_y
    double curv_x
    double curv_y

cdef struct Unit:
    double gx
    double gy
    double phi
    double lam

cdef struct Axle:
    double fx
    double fy
    double fz
    double kappa
    double alpha
    double used
    double asked
    double speed

cdef struct Speeds:
    double u_f
    double w_f
    double u_r
    double w_r
    double cos_d
    double sin_d


cdef inline Unit unit_tire(double kappa, double alpha, double mu, const Tire* t) noexcept nogil:
    cdef Unit out
    cdef double sx = t.kx * kappa / mu
    cdef double sy = t.ky * alpha / mu
    cdef double sx2 = sx * sx
    cdef double lam2 = sx2 + sy * sy
    cdef double lam, weight_x, shape, curv, bs, phi, scale
    if lam2 < SMALL_SLIP_SQUARED:
        out.gx = mu * sx
        out.gy = mu * sy
        out.phi = 0.0
        out.lam = 0.0
        return out
    lam = sqrt(lam2)
    weight_x = sx2 / lam2
    shape = weight_x * t.shape_x + (1.0 - weight_x) * t.shape_y
    curv = weight_x * t.curv_x + (1.0 - weight_x) * t.curv_y
    bs = lam / shape
    phi = sin(shape * atan(bs - curv * (bs - atan(bs))))
    scale = mu * phi / lam
    out.gx = scale * sx
    out.gy = scale * sy
    out.phi = phi
    out.lam = lam
    return out


cdef inline double loaded_tire_fx(
    double kappa, double alpha, double normal_load_n, double mu, const Tire* t
) noexcept nogil:
    if normal_load_n <= 0.0:
        return 0.0
    cdef double sx = t.kx * kappa / mu
    cdef double sy = t.ky * alpha / mu
    cdef double sx2 = sx * sx
    cdef double lam2 = sx2 + sy * sy
    cdef double lam, weight_x, shape, curv, bs, phi
    if lam2 < SMALL_SLIP_SQUARED:
        return mu * normal_load_n * sx
    lam = sqrt(lam2)
    weight_x = sx2 / lam2
    shape = weight_x * t.shape_x + (1.0 - weight_x) * t.shape_y
    curv = weight_x * t.curv_x + (1.0 - weight_x) * t.curv_y
    bs = lam / shape
    phi = sin(shape * atan(bs - curv * (bs - atan(bs))))
    return mu * normal_load_n * phi / lam * sx


cdef inline double follow_axle(
    double omega0, double speed1, double speed0, double radius
) noexcept nogil:
    cdef double omega
    if omega0 > 0.0:
        omega = omega0 + (speed1 - speed0) / radius
        return 0.0 if 0.0 > omega else omega
    return 0.0


cdef Tire tire_struct(object tire):
    cdef Tire t
    t.kx = tire.longitudinal_stiffness_per_load
    t.ky = tire.cornering_stiffness_per_load_1_per_rad
    t.shape_x = tire.shape_longitudinal
    t.shape_y = tire.shape_lateral
    t.curv_x = tire.curvature_longitudinal
    t.curv_y = tire.curvature_lateral
    return t


cdef tuple axle_tuple(const Axle* a):
    return (a.fx, a.fy, a.fz, a.kappa, a.alpha, a.used, a.asked, a.speed)


cdef Axle axle_from(tuple values):
    cdef Axle a
    a.fx, a.fy, a.fz, a.kappa, a.alpha, a.used, a.asked, a.speed = values
    return a


cdef class CompiledPlantKernel:
    """The plant's step for one vehicle, compiled; see the module docstring.

    Built from a :class:`~mufusion.vehicle.plant_kernel.PlantKernel`, whose constants it copies
    (so both kernels use the very same doubles), and the module constants the Python kernel
    reads (gravity, the slip-speed floor, the slip step of the tangent stiffness).
    :meth:`step` has the Python kernel's contract.
    """

    cdef double dt, g_lf, g_lr, h, inertia, lf, lr, mass, max_steer_rate, min_denominator
    cdef double radius, steer_tau, torque_tau, weight, wheelbase, yaw_inertia
    cdef double gravity, slip_floor, slip_step
    cdef object _tire_f_obj, _tire_r_obj
    cdef Tire _tire_f, _tire_r

    def __init__(self, kernel, double gravity, double slip_floor, double slip_step):
        self.gravity, self.slip_floor, self.slip_step = gravity, slip_floor, slip_step
        self.dt = kernel.dt
        self.g_lf, self.g_lr = kernel.g_lf, kernel.g_lr
        self.h = kernel.h
        self.inertia = kernel.inertia
        self.lf, self.lr = kernel.lf, kernel.lr
        self.mass = kernel.mass
        self.max_steer_rate = kernel.max_steer_rate
        self.min_denominator = kernel.min_denominator
        self.radius = kernel.radius
        self.steer_tau = kernel.steer_tau
        self.torque_tau = kernel.torque_tau
        self.weight = kernel.weight
        self.wheelbase = kernel.wheelbase
        self.yaw_inertia = kernel.yaw_inertia
        self._tire_f_obj = None
        self._tire_r_obj = None

    cdef inline Speeds wheel_speeds(
        self, double vx, double vy, double yaw_rate, double steer
    ) noexcept nogil:
        cdef Speeds s
        cdef double lateral_f = vy + self.lf * yaw_rate
        s.cos_d = cos(steer)
        s.sin_d = sin(steer)
        s.u_f = vx * s.cos_d + lateral_f * s.sin_d
        s.w_f = -vx * s.sin_d + lateral_f * s.cos_d
        s.u_r = vx
        s.w_r = vy - self.lr * yaw_rate
        return s

    cdef void axles(
        self, const Speeds* sp, double omega_f, double omega_r, double mu_f, double mu_r,
        Axle* front, Axle* rear,
    ) noexcept nogil:
        cdef double radius = self.radius
        cdef double den_f = fabs(sp.u_f)
        cdef double den_r = fabs(sp.u_r)
        cdef double floor = self.slip_floor
        den_f = floor if floor > den_f else den_f
        den_r = floor if floor > den_r else den_r
        cdef double kappa_f = (radius * omega_f - sp.u_f) / den_f
        cdef double kappa_r = (radius * omega_r - sp.u_r) / den_r
        cdef double alpha_f = -atan(sp.w_f / den_f)
        cdef double alpha_r = -atan(sp.w_r / den_r)
        cdef Unit gf = unit_tire(kappa_f, alpha_f, mu_f, &self._tire_f)
        cdef Unit gr = unit_tire(kappa_r, alpha_r, mu_r, &self._tire_r)
        cdef double h = self.h
        cdef double g_front = gf.gx * sp.cos_d - gf.gy * sp.sin_d
        cdef double denominator = self.wheelbase + h * (g_front - gr.gx)
        if self.min_denominator > denominator:
            denominator = self.min_denominator
        cdef double accel = self.gravity * (g_front * self.lr + gr.gx * self.lf) / denominator
        cdef double fzf = self.weight * (self.g_lr - accel * h)
        fzf = 0.0 if 0.0 > fzf else fzf
        cdef double fzr = self.weight * (self.g_lf + accel * h)
        fzr = 0.0 if 0.0 > fzr else fzr
        front.fx = gf.gx * fzf
        front.fy = gf.gy * fzf
        front.fz = fzf
        front.kappa = kappa_f
        front.alpha = alpha_f
        front.used = gf.phi if fzf > 0.0 else 0.0
        front.asked = gf.lam if fzf > 0.0 else 0.0
        front.speed = sp.u_f
        rear.fx = gr.gx * fzr
        rear.fy = gr.gy * fzr
        rear.fz = fzr
        rear.kappa = kappa_r
        rear.alpha = alpha_r
        rear.used = gr.phi if fzr > 0.0 else 0.0
        rear.asked = gr.lam if fzr > 0.0 else 0.0
        rear.speed = sp.u_r

    cdef void rates(
        self, double psi, double vx, double vy, double yaw_rate, double steer,
        double torque_f, double torque_r, double cos_d, double sin_d,
        const Axle* front, const Axle* rear, const double* command, double* out,
    ) noexcept nogil:
        cdef double fy_f = front.fy * command[5]  # the share ESC's braked wheel leaves
        cdef double fx_front_body = front.fx * cos_d - fy_f * sin_d
        cdef double fy_front_body = front.fx * sin_d + fy_f * cos_d
        cdef double m = self.mass
        cdef double cos_p = cos(psi)
        cdef double sin_p = sin(psi)
        cdef double max_rate = self.max_steer_rate
        cdef double steer_rate = (command[0] - steer) / self.steer_tau
        if -max_rate > steer_rate:
            steer_rate = -max_rate
        if max_rate < steer_rate:
            steer_rate = max_rate
        out[0] = vx * cos_p - vy * sin_p
        out[1] = vx * sin_p + vy * cos_p
        out[2] = yaw_rate
        out[3] = (fx_front_body + rear.fx + command[4]) / m + vy * yaw_rate
        out[4] = (fy_front_body + rear.fy) / m - vx * yaw_rate
        out[5] = (self.lf * fy_front_body - self.lr * rear.fy + command[3]) / self.yaw_inertia
        out[6] = steer_rate
        out[7] = (command[1] - torque_f) / self.torque_tau
        out[8] = (command[2] - torque_r) / self.torque_tau

    cdef void stage(
        self, double scale, const double* x0, const double* k, double omega_f0,
        double omega_r0, double u_f0, double u_r0, double mu_f, double mu_r,
        const double* command, double* out,
    ) noexcept nogil:
        # The state x₀ + scale · k (its position does not enter the rates).
        cdef double vx = x0[3] + scale * k[3]
        cdef double vy = x0[4] + scale * k[4]
        cdef double r = x0[5] + scale * k[5]
        cdef double steer = x0[6] + scale * k[6]
        cdef Speeds sp = self.wheel_speeds(vx, vy, r, steer)
        cdef Axle front, rear
        self.axles(
            &sp, follow_axle(omega_f0, sp.u_f, u_f0, self.radius),
            follow_axle(omega_r0, sp.u_r, u_r0, self.radius), mu_f, mu_r, &front, &rear,
        )
        self.rates(x0[2] + scale * k[2], vx, vy, r, steer, x0[7] + scale * k[7],
                   x0[8] + scale * k[8], sp.cos_d, sp.sin_d, &front, &rear, command, out)

    cdef double wheel(
        self, double omega0, double predicted, double torque, const Axle* axle, double mu,
        const Tire* tire,
    ) noexcept nogil:
        cdef double dt = self.dt, radius = self.radius, inertia = self.inertia
        cdef double step = self.slip_step, floor = self.slip_floor
        cdef double fx_plus = loaded_tire_fx(axle.kappa + step, axle.alpha, axle.fz, mu, tire)
        cdef double rise = (fx_plus - axle.fx) / step
        cdef double speed = fabs(axle.speed)
        rise = 0.0 if 0.0 > rise else rise
        speed = floor if floor > speed else speed
        cdef double slope = rise * radius / speed
        cdef double effective = inertia + dt * radius * slope
        cdef double drive = 0.0 if 0.0 > torque else torque
        cdef double brake = 0.0 if 0.0 > -torque else -torque
        cdef double free = (
            inertia * omega0 + dt * (drive - radius * axle.fx + radius * slope * predicted)
        ) / effective
        cdef double hold = dt * brake / effective
        if free > hold:
            return free - hold
        if free < -hold:
            return free + hold
        return 0.0

    def step(
        self,
        tuple chassis0,
        double omega_f0,
        double omega_r0,
        tuple command,
        double mu_f,
        double mu_r,
        tire_f,
        tire_r,
        first_axles,
    ):
        """:meth:`PlantKernel.step <mufusion.vehicle.plant_kernel.PlantKernel.step>`."""
        if tire_f is not self._tire_f_obj:
            self._tire_f = tire_struct(tire_f)
            self._tire_f_obj = tire_f
        if tire_r is not self._tire_r_obj:
            self._tire_r = tire_struct(tire_r)
            self._tire_r_obj = tire_r
        cdef double x0[9]
        cdef double cmd[6]
        cdef double k1[9]
        cdef double k2[9]
        cdef double k3[9]
        cdef double k4[9]
        cdef double x1[9]
        cdef int i
        for i in range(9):
            x0[i] = chassis0[i]
        for i in range(3):
            cmd[i] = command[i]
        # The stability control's yaw moment, braking force and the front axle's lateral share,
        # if given (plant_kernel.Command).
        cmd[3] = command[3] if len(command) > 3 else 0.0
        cmd[4] = command[4] if len(command) > 3 else 0.0
        cmd[5] = command[5] if len(command) > 5 else 1.0
        cdef double dt = self.dt, radius = self.radius
        cdef Axle front, rear
        cdef Speeds sp0 = self.wheel_speeds(x0[3], x0[4], x0[5], x0[6])
        cdef double u_f0 = sp0.u_f, u_r0 = sp0.u_r
        if first_axles is None:
            self.axles(&sp0, follow_axle(omega_f0, u_f0, u_f0, radius),
                       follow_axle(omega_r0, u_r0, u_r0, radius), mu_f, mu_r, &front, &rear)
        else:
            front = axle_from(first_axles[0])
            rear = axle_from(first_axles[1])
        with nogil:
            self.rates(x0[2], x0[3], x0[4], x0[5], x0[6], x0[7], x0[8], sp0.cos_d, sp0.sin_d,
                       &front, &rear, cmd, k1)
            self.stage(0.5 * dt, x0, k1, omega_f0, omega_r0, u_f0, u_r0, mu_f, mu_r, cmd, k2)
            self.stage(0.5 * dt, x0, k2, omega_f0, omega_r0, u_f0, u_r0, mu_f, mu_r, cmd, k3)
            self.stage(dt, x0, k3, omega_f0, omega_r0, u_f0, u_r0, mu_f, mu_r, cmd, k4)
        cdef double sixth = dt / 6.0
        for i in range(9):
            x1[i] = x0[i] + sixth * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i])
        # Implicit wheel step at the new chassis state.
        cdef Speeds sp1 = self.wheel_speeds(x1[3], x1[4], x1[5], x1[6])
        cdef double predicted_f = follow_axle(omega_f0, sp1.u_f, u_f0, radius)
        cdef double predicted_r = follow_axle(omega_r0, sp1.u_r, u_r0, radius)
        self.axles(&sp1, predicted_f, predicted_r, mu_f, mu_r, &front, &rear)
        cdef double omega_f = self.wheel(omega_f0, predicted_f, x1[7], &front, mu_f,
                                         &self._tire_f)
        cdef double omega_r = self.wheel(omega_r0, predicted_r, x1[8], &rear, mu_r,
                                         &self._tire_r)
        # The output's axles at the new state with the new wheel spins.
        self.axles(&sp1, omega_f, omega_r, mu_f, mu_r, &front, &rear)
        return (
            (x1[0], x1[1], x1[2], x1[3], x1[4], x1[5], omega_f, omega_r, x1[6], x1[7], x1[8]),
            (axle_tuple(&front), axle_tuple(&rear)),
            sp1.cos_d,
            sp1.sin_d,
        )
