!> Forward-mode algorithmic differentiation by dual numbers.
!>
!> Design: a dual_t is a value and a fixed-length vector of `dual_size` directional
!> derivatives (tangents), both plain components: no allocation anywhere, so duals
!> live on the stack, in arrays and in elemental expressions inside hot loops at the
!> cost of (1 + dual_size) flops per real flop. One pass propagates up to dual_size
!> seeded directions (e.g. the 6 + 6 velocity directions of two rigid bodies plus time);
!> more directions take several passes. Components are not default-initialised (that
!> would cost a write per temporary): build duals with dual_constant, dual_variable or
!> dual_seed, or by assignment from a real (zero tangent).
!>
!> Overloaded: + - * / ** (integer, real and dual exponents), comparisons (on values),
!> assignment from real, the elemental intrinsics sqrt exp log sin cos tan asin acos
!> atan atan2 sinh cosh tanh abs max min, and dot_product, matmul, sum, norm2 for
!> dual arrays mixed with real arrays.
module flexmbs_mbs_dual
    use flexmbs_core_kinds, only: wp
    implicit none
    private

    !> Number of tangent directions carried by every dual number.
    integer, parameter, public :: dual_size = 16

    !> A dual number: a value and its derivatives along up to dual_size seeded
    !> directions (components left undefined; see the module).
    type, public :: dual_t
        real(wp) :: val !! value
        real(wp) :: der(dual_size) !! derivatives along the seeded directions
    end type dual_t

    public :: dual_constant, dual_variable, dual_seed, dual_value, dual_derivative
    public :: operator(+), operator(-), operator(*), operator(/), operator(**)
    public :: operator(==), operator(/=), operator(<), operator(<=), operator(>), &
        operator(>=)
    public :: assignment(=)
    public :: sqrt, exp, log, sin, cos, tan, asin, acos, atan, atan2, sinh, cosh, tanh, &
        abs, max, min, dot_product, matmul, sum, norm2

    !> Sum of duals, of a dual and a real (either order), and unary plus.
    interface operator(+)
        module procedure add_dd, add_dr, add_rd, plus_d
    end interface
    !> Difference of duals, of a dual and a real (either order), and negation.
    interface operator(-)
        module procedure sub_dd, sub_dr, sub_rd, minus_d
    end interface
    !> Product by the product rule (dual · dual), or scaling by a real.
    interface operator(*)
        module procedure mul_dd, mul_dr, mul_rd
    end interface
    !> Quotient by the quotient rule (dual / dual), or with a real on either side.
    interface operator(/)
        module procedure div_dd, div_dr, div_rd
    end interface
    !> Power with an integer, real or dual exponent; the dual exponent takes
    !> exp(b log a) and needs a > 0.
    interface operator(**)
        module procedure pow_di, pow_dr, pow_dd
    end interface
    !> Comparisons look at the values only (the tangents do not take part), so
    !> branches on duals follow the real computation.
    interface operator(==)
        module procedure eq_dd, eq_dr, eq_rd
    end interface
    !> Inequality of values (tangents ignored).
    interface operator(/=)
        module procedure ne_dd, ne_dr, ne_rd
    end interface
    !> Order of values (tangents ignored).
    interface operator(<)
        module procedure lt_dd, lt_dr, lt_rd
    end interface
    !> Order of values (tangents ignored).
    interface operator(<=)
        module procedure le_dd, le_dr, le_rd
    end interface
    !> Order of values (tangents ignored).
    interface operator(>)
        module procedure gt_dd, gt_dr, gt_rd
    end interface
    !> Order of values (tangents ignored).
    interface operator(>=)
        module procedure ge_dd, ge_dr, ge_rd
    end interface
    !> A real assigned to a dual: a constant, zero tangents.
    interface assignment(=)
        module procedure assign_r
    end interface
    !> Square root; the tangent is Inf or NaN at 0, where sqrt has no derivative.
    interface sqrt
        module procedure sqrt_d
    end interface
    !> Exponential: tangent exp(a) da.
    interface exp
        module procedure exp_d
    end interface
    !> Natural logarithm: tangent da / a.
    interface log
        module procedure log_d
    end interface
    !> Sine: tangent cos(a) da.
    interface sin
        module procedure sin_d
    end interface
    !> Cosine: tangent −sin(a) da.
    interface cos
        module procedure cos_d
    end interface
    !> Tangent function: derivative 1 + tan²(a).
    interface tan
        module procedure tan_d
    end interface
    !> Arcsine: derivative 1 / sqrt(1 − a²), infinite at |a| = 1.
    interface asin
        module procedure asin_d
    end interface
    !> Arccosine: derivative −1 / sqrt(1 − a²), infinite at |a| = 1.
    interface acos
        module procedure acos_d
    end interface
    !> Arctangent: derivative 1 / (1 + a²).
    interface atan
        module procedure atan_d
    end interface
    !> atan2(y, x) with dual or real arguments: derivative
    !> (x dy − y dx) / (x² + y²).
    interface atan2
        module procedure atan2_dd, atan2_dr, atan2_rd
    end interface
    !> Hyperbolic sine: derivative cosh(a).
    interface sinh
        module procedure sinh_d
    end interface
    !> Hyperbolic cosine: derivative sinh(a).
    interface cosh
        module procedure cosh_d
    end interface
    !> Hyperbolic tangent: derivative 1 − tanh²(a).
    interface tanh
        module procedure tanh_d
    end interface
    !> |a|, with the derivative of the positive branch at 0.
    interface abs
        module procedure abs_d
    end interface
    !> The larger value with its own tangents (a on ties), duals and reals mixed.
    interface max
        module procedure max_dd, max_dr, max_rd
    end interface
    !> The smaller value with its own tangents (a on ties), duals and reals mixed.
    interface min
        module procedure min_dd, min_dr, min_rd
    end interface
    !> Dot product of dual vectors, or of a dual and a real vector.
    interface dot_product
        module procedure dot_dd, dot_dr, dot_rd
    end interface
    !> Matrix-vector and matrix-matrix products with dual and real operands.
    interface matmul
        module procedure matvec_dd, matvec_dr, matvec_rd, matmat_dd, matmat_dr, matmat_rd
    end interface
    !> Sum of a dual vector.
    interface sum
        module procedure sum_d
    end interface
    !> Euclidean norm of a dual vector; no derivative at the zero vector.
    interface norm2
        module procedure norm2_d
    end interface

contains

    ! ------------------------------------------------------------ construction

    !> A constant: value x, zero tangents.
    elemental function dual_constant(x) result(d)
        real(wp), intent(in) :: x
        type(dual_t) :: d
        d%val = x
        d%der = 0.0_wp
    end function dual_constant

    !> The independent variable number k (1 <= k <= dual_size): tangent e_k.
    elemental function dual_variable(x, k) result(d)
        real(wp), intent(in) :: x
        integer, intent(in) :: k
        type(dual_t) :: d
        d%val = x
        d%der = 0.0_wp
        d%der(k) = 1.0_wp
    end function dual_variable

    !> Value x with the tangents der (missing trailing directions are zero).
    pure function dual_seed(x, der) result(d)
        real(wp), intent(in) :: x, der(:)
        type(dual_t) :: d
        d%val = x
        d%der = 0.0_wp
        d%der(1:size(der)) = der
    end function dual_seed

    !> The value of a dual, its tangents dropped.
    elemental function dual_value(d) result(x)
        type(dual_t), intent(in) :: d
        real(wp) :: x
        x = d%val
    end function dual_value

    !> The derivative along direction k.
    elemental function dual_derivative(d, k) result(x)
        type(dual_t), intent(in) :: d
        integer, intent(in) :: k
        real(wp) :: x
        x = d%der(k)
    end function dual_derivative

    elemental subroutine assign_r(d, x)
        type(dual_t), intent(out) :: d
        real(wp), intent(in) :: x
        d%val = x
        d%der = 0.0_wp
    end subroutine assign_r

    ! ------------------------------------------------------------- arithmetic

    elemental function add_dd(a, b) result(c)
        type(dual_t), intent(in) :: a, b
        type(dual_t) :: c
        c%val = a%val + b%val
        c%der = a%der + b%der
    end function add_dd

    elemental function add_dr(a, b) result(c)
        type(dual_t), intent(in) :: a
        real(wp), intent(in) :: b
        type(dual_t) :: c
        c%val = a%val + b
        c%der = a%der
    end function add_dr

    elemental function add_rd(a, b) result(c)
        real(wp), intent(in) :: a
        type(dual_t), intent(in) :: b
        type(dual_t) :: c
        c%val = a + b%val
        c%der = b%der
    end function add_rd

    elemental function plus_d(a) result(c)
        type(dual_t), intent(in) :: a
        type(dual_t) :: c
        c = a
    end function plus_d

    elemental function sub_dd(a, b) result(c)
        type(dual_t), intent(in) :: a, b
        type(dual_t) :: c
        c%val = a%val - b%val
        c%der = a%der - b%der
    end function sub_dd

    elemental function sub_dr(a, b) result(c)
        type(dual_t), intent(in) :: a
        real(wp), intent(in) :: b
        type(dual_t) :: c
        c%val = a%val - b
        c%der = a%der
    end function sub_dr

    elemental function sub_rd(a, b) result(c)
        real(wp), intent(in) :: a
        type(dual_t), intent(in) :: b
        type(dual_t) :: c
        c%val = a - b%val
        c%der = -b%der
    end function sub_rd

    elemental function minus_d(a) result(c)
        type(dual_t), intent(in) :: a
        type(dual_t) :: c
        c%val = -a%val
        c%der = -a%der
    end function minus_d

    elemental function mul_dd(a, b) result(c)
        type(dual_t), intent(in) :: a, b
        type(dual_t) :: c
        c%val = a%val * b%val
        c%der = a%der * b%val + a%val * b%der
    end function mul_dd

    elemental function mul_dr(a, b) result(c)
        type(dual_t), intent(in) :: a
        real(wp), intent(in) :: b
        type(dual_t) :: c
        c%val = a%val * b
        c%der = a%der * b
    end function mul_dr

    elemental function mul_rd(a, b) result(c)
        real(wp), intent(in) :: a
        type(dual_t), intent(in) :: b
        type(dual_t) :: c
        c%val = a * b%val
        c%der = a * b%der
    end function mul_rd

    elemental function div_dd(a, b) result(c)
        type(dual_t), intent(in) :: a, b
        type(dual_t) :: c
        c%val = a%val / b%val
        c%der = (a%der - c%val * b%der) / b%val
    end function div_dd

    elemental function div_dr(a, b) result(c)
        type(dual_t), intent(in) :: a
        real(wp), intent(in) :: b
        type(dual_t) :: c
        c%val = a%val / b
        c%der = a%der / b
    end function div_dr

    elemental function div_rd(a, b) result(c)
        real(wp), intent(in) :: a
        type(dual_t), intent(in) :: b
        type(dual_t) :: c
        c%val = a / b%val
        c%der = (-c%val / b%val) * b%der
    end function div_rd

    elemental function pow_di(a, n) result(c)
        type(dual_t), intent(in) :: a
        integer, intent(in) :: n
        type(dual_t) :: c
        c%val = a%val**n
        if (n == 0) then
            c%der = 0.0_wp
        else
            c%der = (n * a%val**(n - 1)) * a%der
        end if
    end function pow_di

    elemental function pow_dr(a, r) result(c)
        type(dual_t), intent(in) :: a
        real(wp), intent(in) :: r
        type(dual_t) :: c
        c%val = a%val**r
        c%der = (r * a%val**(r - 1.0_wp)) * a%der
    end function pow_dr

    !> a**b = exp(b log a), a > 0.
    elemental function pow_dd(a, b) result(c)
        type(dual_t), intent(in) :: a, b
        type(dual_t) :: c
        c%val = a%val**b%val
        c%der = c%val * (b%der * log(a%val) + (b%val / a%val) * a%der)
    end function pow_dd

    ! ------------------------------------------------------------ comparisons

    elemental logical function eq_dd(a, b)
        type(dual_t), intent(in) :: a, b
        eq_dd = a%val == b%val
    end function eq_dd
    elemental logical function eq_dr(a, b)
        type(dual_t), intent(in) :: a
        real(wp), intent(in) :: b
        eq_dr = a%val == b
    end function eq_dr
    elemental logical function eq_rd(a, b)
        real(wp), intent(in) :: a
        type(dual_t), intent(in) :: b
        eq_rd = a == b%val
    end function eq_rd
    elemental logical function ne_dd(a, b)
        type(dual_t), intent(in) :: a, b
        ne_dd = a%val /= b%val
    end function ne_dd
    elemental logical function ne_dr(a, b)
        type(dual_t), intent(in) :: a
        real(wp), intent(in) :: b
        ne_dr = a%val /= b
    end function ne_dr
    elemental logical function ne_rd(a, b)
        real(wp), intent(in) :: a
        type(dual_t), intent(in) :: b
        ne_rd = a /= b%val
    end function ne_rd
    elemental logical function lt_dd(a, b)
        type(dual_t), intent(in) :: a, b
        lt_dd = a%val < b%val
    end function lt_dd
    elemental logical function lt_dr(a, b)
        type(dual_t), intent(in) :: a
        real(wp), intent(in) :: b
        lt_dr = a%val < b
    end function lt_dr
    elemental logical function lt_rd(a, b)
        real(wp), intent(in) :: a
        type(dual_t), intent(in) :: b
        lt_rd = a < b%val
    end function lt_rd
    elemental logical function le_dd(a, b)
        type(dual_t), intent(in) :: a, b
        le_dd = a%val <= b%val
    end function le_dd
    elemental logical function le_dr(a, b)
        type(dual_t), intent(in) :: a
        real(wp), intent(in) :: b
        le_dr = a%val <= b
    end function le_dr
    elemental logical function le_rd(a, b)
        real(wp), intent(in) :: a
        type(dual_t), intent(in) :: b
        le_rd = a <= b%val
    end function le_rd
    elemental logical function gt_dd(a, b)
        type(dual_t), intent(in) :: a, b
        gt_dd = a%val > b%val
    end function gt_dd
    elemental logical function gt_dr(a, b)
        type(dual_t), intent(in) :: a
        real(wp), intent(in) :: b
        gt_dr = a%val > b
    end function gt_dr
    elemental logical function gt_rd(a, b)
        real(wp), intent(in) :: a
        type(dual_t), intent(in) :: b
        gt_rd = a > b%val
    end function gt_rd
    elemental logical function ge_dd(a, b)
        type(dual_t), intent(in) :: a, b
        ge_dd = a%val >= b%val
    end function ge_dd
    elemental logical function ge_dr(a, b)
        type(dual_t), intent(in) :: a
        real(wp), intent(in) :: b
        ge_dr = a%val >= b
    end function ge_dr
    elemental logical function ge_rd(a, b)
        real(wp), intent(in) :: a
        type(dual_t), intent(in) :: b
        ge_rd = a >= b%val
    end function ge_rd

    ! ------------------------------------------------------------- intrinsics

    !> The derivative of sqrt is infinite at 0: the tangent becomes Inf/NaN there.
    elemental function sqrt_d(a) result(c)
        type(dual_t), intent(in) :: a
        type(dual_t) :: c
        c%val = sqrt(a%val)
        c%der = a%der / (2.0_wp * c%val)
    end function sqrt_d

    elemental function exp_d(a) result(c)
        type(dual_t), intent(in) :: a
        type(dual_t) :: c
        c%val = exp(a%val)
        c%der = c%val * a%der
    end function exp_d

    elemental function log_d(a) result(c)
        type(dual_t), intent(in) :: a
        type(dual_t) :: c
        c%val = log(a%val)
        c%der = a%der / a%val
    end function log_d

    elemental function sin_d(a) result(c)
        type(dual_t), intent(in) :: a
        type(dual_t) :: c
        c%val = sin(a%val)
        c%der = cos(a%val) * a%der
    end function sin_d

    elemental function cos_d(a) result(c)
        type(dual_t), intent(in) :: a
        type(dual_t) :: c
        c%val = cos(a%val)
        c%der = -sin(a%val) * a%der
    end function cos_d

    elemental function tan_d(a) result(c)
        type(dual_t), intent(in) :: a
        type(dual_t) :: c
        c%val = tan(a%val)
        c%der = (1.0_wp + c%val**2) * a%der
    end function tan_d

    elemental function asin_d(a) result(c)
        type(dual_t), intent(in) :: a
        type(dual_t) :: c
        c%val = asin(a%val)
        c%der = a%der / sqrt(1.0_wp - a%val**2)
    end function asin_d

    elemental function acos_d(a) result(c)
        type(dual_t), intent(in) :: a
        type(dual_t) :: c
        c%val = acos(a%val)
        c%der = -a%der / sqrt(1.0_wp - a%val**2)
    end function acos_d

    elemental function atan_d(a) result(c)
        type(dual_t), intent(in) :: a
        type(dual_t) :: c
        c%val = atan(a%val)
        c%der = a%der / (1.0_wp + a%val**2)
    end function atan_d

    !> d atan2(y, x) = (x dy - y dx) / (x^2 + y^2).
    elemental function atan2_dd(y, x) result(c)
        type(dual_t), intent(in) :: y, x
        type(dual_t) :: c
        c%val = atan2(y%val, x%val)
        c%der = (x%val * y%der - y%val * x%der) / (x%val**2 + y%val**2)
    end function atan2_dd

    elemental function atan2_dr(y, x) result(c)
        type(dual_t), intent(in) :: y
        real(wp), intent(in) :: x
        type(dual_t) :: c
        c%val = atan2(y%val, x)
        c%der = (x / (x**2 + y%val**2)) * y%der
    end function atan2_dr

    elemental function atan2_rd(y, x) result(c)
        real(wp), intent(in) :: y
        type(dual_t), intent(in) :: x
        type(dual_t) :: c
        c%val = atan2(y, x%val)
        c%der = (-y / (x%val**2 + y**2)) * x%der
    end function atan2_rd

    elemental function sinh_d(a) result(c)
        type(dual_t), intent(in) :: a
        type(dual_t) :: c
        c%val = sinh(a%val)
        c%der = cosh(a%val) * a%der
    end function sinh_d

    elemental function cosh_d(a) result(c)
        type(dual_t), intent(in) :: a
        type(dual_t) :: c
        c%val = cosh(a%val)
        c%der = sinh(a%val) * a%der
    end function cosh_d

    elemental function tanh_d(a) result(c)
        type(dual_t), intent(in) :: a
        type(dual_t) :: c
        c%val = tanh(a%val)
        c%der = (1.0_wp - c%val**2) * a%der
    end function tanh_d

    !> |a|, with the one-sided derivative of the positive branch at 0.
    elemental function abs_d(a) result(c)
        type(dual_t), intent(in) :: a
        type(dual_t) :: c
        if (a%val < 0.0_wp) then
            c = -a
        else
            c = a
        end if
    end function abs_d

    elemental function max_dd(a, b) result(c)
        type(dual_t), intent(in) :: a, b
        type(dual_t) :: c
        if (a%val >= b%val) then
            c = a
        else
            c = b
        end if
    end function max_dd

    elemental function max_dr(a, b) result(c)
        type(dual_t), intent(in) :: a
        real(wp), intent(in) :: b
        type(dual_t) :: c
        c = max_dd(a, dual_constant(b))
    end function max_dr

    elemental function max_rd(a, b) result(c)
        real(wp), intent(in) :: a
        type(dual_t), intent(in) :: b
        type(dual_t) :: c
        c = max_dd(dual_constant(a), b)
    end function max_rd

    elemental function min_dd(a, b) result(c)
        type(dual_t), intent(in) :: a, b
        type(dual_t) :: c
        if (a%val <= b%val) then
            c = a
        else
            c = b
        end if
    end function min_dd

    elemental function min_dr(a, b) result(c)
        type(dual_t), intent(in) :: a
        real(wp), intent(in) :: b
        type(dual_t) :: c
        c = min_dd(a, dual_constant(b))
    end function min_dr

    elemental function min_rd(a, b) result(c)
        real(wp), intent(in) :: a
        type(dual_t), intent(in) :: b
        type(dual_t) :: c
        c = min_dd(dual_constant(a), b)
    end function min_rd

    ! ---------------------------------------------------------- array helpers

    pure function dot_dd(a, b) result(c)
        type(dual_t), intent(in) :: a(:), b(:)
        type(dual_t) :: c
        integer :: i
        c = 0.0_wp
        do i = 1, size(a)
            c%val = c%val + a(i)%val * b(i)%val
            c%der = c%der + a(i)%der * b(i)%val + a(i)%val * b(i)%der
        end do
    end function dot_dd

    pure function dot_dr(a, b) result(c)
        type(dual_t), intent(in) :: a(:)
        real(wp), intent(in) :: b(:)
        type(dual_t) :: c
        integer :: i
        c = 0.0_wp
        do i = 1, size(a)
            c%val = c%val + a(i)%val * b(i)
            c%der = c%der + a(i)%der * b(i)
        end do
    end function dot_dr

    pure function dot_rd(a, b) result(c)
        real(wp), intent(in) :: a(:)
        type(dual_t), intent(in) :: b(:)
        type(dual_t) :: c
        c = dot_dr(b, a)
    end function dot_rd

    pure function matvec_dd(a, x) result(y)
        type(dual_t), intent(in) :: a(:, :), x(:)
        type(dual_t) :: y(size(a, 1))
        integer :: i
        do i = 1, size(a, 1)
            y(i) = dot_dd(a(i, :), x)
        end do
    end function matvec_dd

    pure function matvec_dr(a, x) result(y)
        type(dual_t), intent(in) :: a(:, :)
        real(wp), intent(in) :: x(:)
        type(dual_t) :: y(size(a, 1))
        integer :: i
        do i = 1, size(a, 1)
            y(i) = dot_dr(a(i, :), x)
        end do
    end function matvec_dr

    pure function matvec_rd(a, x) result(y)
        real(wp), intent(in) :: a(:, :)
        type(dual_t), intent(in) :: x(:)
        type(dual_t) :: y(size(a, 1))
        integer :: i
        do i = 1, size(a, 1)
            y(i) = dot_dr(x, a(i, :))
        end do
    end function matvec_rd

    pure function matmat_dd(a, b) result(c)
        type(dual_t), intent(in) :: a(:, :), b(:, :)
        type(dual_t) :: c(size(a, 1), size(b, 2))
        integer :: j
        do j = 1, size(b, 2)
            c(:, j) = matvec_dd(a, b(:, j))
        end do
    end function matmat_dd

    pure function matmat_dr(a, b) result(c)
        type(dual_t), intent(in) :: a(:, :)
        real(wp), intent(in) :: b(:, :)
        type(dual_t) :: c(size(a, 1), size(b, 2))
        integer :: j
        do j = 1, size(b, 2)
            c(:, j) = matvec_dr(a, b(:, j))
        end do
    end function matmat_dr

    pure function matmat_rd(a, b) result(c)
        real(wp), intent(in) :: a(:, :)
        type(dual_t), intent(in) :: b(:, :)
        type(dual_t) :: c(size(a, 1), size(b, 2))
        integer :: j
        do j = 1, size(b, 2)
            c(:, j) = matvec_rd(a, b(:, j))
        end do
    end function matmat_rd

    pure function sum_d(a) result(c)
        type(dual_t), intent(in) :: a(:)
        type(dual_t) :: c
        integer :: i
        c = 0.0_wp
        do i = 1, size(a)
            c%val = c%val + a(i)%val
            c%der = c%der + a(i)%der
        end do
    end function sum_d

    !> Euclidean norm; its derivative is undefined at the zero vector.
    pure function norm2_d(a) result(c)
        type(dual_t), intent(in) :: a(:)
        type(dual_t) :: c
        c = sqrt(dot_dd(a, a))
    end function norm2_d
end module flexmbs_mbs_dual
