!> Second-order Taylor arithmetic along one direction (jets): a jet_t holds
!> f(s) = f0 + f1 s + f2 s²/2 near s = 0, i.e. the value and the first two
!> derivatives of a quantity along a curve. Propagating jets through a
!> formula gives its second derivative along the curve in one pass at a few
!> flops per operation (Griewank & Walther 2008, ch. 13: univariate Taylor
!> propagation). The constraint primitives on jets give γ = d²c/ds² along the
!> markers' motion at zero accelerations (flexmbs_mbs_system, 'ad').
!>
!> Overloaded: + - * / ** (integer exponent), assignment from real, sqrt sin
!> cos, matmul of jet and real matrices and vectors — what rotation.inc and
!> constraint_primitives.inc use.
module flexmbs_mbs_jet
    use flexmbs_core_kinds, only: wp
    implicit none
    private

    !> A jet: f0 + f1 s + f2 s²/2, the value and the first two derivatives of
    !> a quantity along one curve s.
    type, public :: jet_t
        real(wp) :: f0 !! value
        real(wp) :: f1 !! first derivative
        real(wp) :: f2 !! second derivative
    end type jet_t

    public :: operator(+), operator(-), operator(*), operator(/), operator(**)
    public :: assignment(=), sqrt, sin, cos, matmul

    !> Sum of jets, of a jet and a real (either order), and unary plus.
    interface operator(+)
        module procedure add_jj, add_jr, add_rj, plus_j
    end interface
    !> Difference of jets, of a jet and a real (either order), and negation.
    interface operator(-)
        module procedure sub_jj, sub_jr, sub_rj, minus_j
    end interface
    !> Product by Leibniz's rule, (ab)'' = a''b + 2a'b' + ab'', or scaling by a real.
    interface operator(*)
        module procedure mul_jj, mul_jr, mul_rj
    end interface
    !> Quotient of jets, or with a real on either side.
    interface operator(/)
        module procedure div_jj, div_jr, div_rj
    end interface
    !> Integer power of a jet.
    interface operator(**)
        module procedure pow_ji
    end interface
    !> A real assigned to a jet: a constant, zero derivatives.
    interface assignment(=)
        module procedure assign_r
    end interface
    !> Square root of a jet (no derivatives at 0).
    interface sqrt
        module procedure sqrt_j
    end interface
    !> Sine of a jet.
    interface sin
        module procedure sin_j
    end interface
    !> Cosine of a jet.
    interface cos
        module procedure cos_j
    end interface
    !> Matrix-vector and matrix-matrix products with jet and real operands.
    interface matmul
        module procedure matvec_jj, matvec_jr, matvec_rj, matmat_jj, matmat_jr, matmat_rj
    end interface

contains

    elemental subroutine assign_r(a, x)
        type(jet_t), intent(out) :: a
        real(wp), intent(in) :: x
        a = lift(x)
    end subroutine assign_r

    elemental function add_jj(a, b) result(c)
        type(jet_t), intent(in) :: a, b
        type(jet_t) :: c
        c = jet_t(a%f0 + b%f0, a%f1 + b%f1, a%f2 + b%f2)
    end function add_jj

    elemental function add_jr(a, b) result(c)
        type(jet_t), intent(in) :: a
        real(wp), intent(in) :: b
        type(jet_t) :: c
        c = jet_t(a%f0 + b, a%f1, a%f2)
    end function add_jr

    elemental function add_rj(a, b) result(c)
        real(wp), intent(in) :: a
        type(jet_t), intent(in) :: b
        type(jet_t) :: c
        c = jet_t(a + b%f0, b%f1, b%f2)
    end function add_rj

    elemental function plus_j(a) result(c)
        type(jet_t), intent(in) :: a
        type(jet_t) :: c
        c = a
    end function plus_j

    elemental function sub_jj(a, b) result(c)
        type(jet_t), intent(in) :: a, b
        type(jet_t) :: c
        c = jet_t(a%f0 - b%f0, a%f1 - b%f1, a%f2 - b%f2)
    end function sub_jj

    elemental function sub_jr(a, b) result(c)
        type(jet_t), intent(in) :: a
        real(wp), intent(in) :: b
        type(jet_t) :: c
        c = jet_t(a%f0 - b, a%f1, a%f2)
    end function sub_jr

    elemental function sub_rj(a, b) result(c)
        real(wp), intent(in) :: a
        type(jet_t), intent(in) :: b
        type(jet_t) :: c
        c = jet_t(a - b%f0, -b%f1, -b%f2)
    end function sub_rj

    elemental function minus_j(a) result(c)
        type(jet_t), intent(in) :: a
        type(jet_t) :: c
        c = jet_t(-a%f0, -a%f1, -a%f2)
    end function minus_j

    !> (ab)'' = a'' b + 2 a' b' + a b''.
    elemental function mul_jj(a, b) result(c)
        type(jet_t), intent(in) :: a, b
        type(jet_t) :: c
        c = jet_t(a%f0 * b%f0, a%f0 * b%f1 + a%f1 * b%f0, &
                  a%f0 * b%f2 + 2.0_wp * a%f1 * b%f1 + a%f2 * b%f0)
    end function mul_jj

    elemental function mul_jr(a, b) result(c)
        type(jet_t), intent(in) :: a
        real(wp), intent(in) :: b
        type(jet_t) :: c
        c = jet_t(a%f0 * b, a%f1 * b, a%f2 * b)
    end function mul_jr

    elemental function mul_rj(a, b) result(c)
        real(wp), intent(in) :: a
        type(jet_t), intent(in) :: b
        type(jet_t) :: c
        c = jet_t(a * b%f0, a * b%f1, a * b%f2)
    end function mul_rj

    !> c = a/b from c b = a: c' = (a' − c b')/b, c'' = (a'' − 2 c' b' − c b'')/b.
    elemental function div_jj(a, b) result(c)
        type(jet_t), intent(in) :: a, b
        type(jet_t) :: c
        c%f0 = a%f0 / b%f0
        c%f1 = (a%f1 - c%f0 * b%f1) / b%f0
        c%f2 = (a%f2 - 2.0_wp * c%f1 * b%f1 - c%f0 * b%f2) / b%f0
    end function div_jj

    elemental function div_jr(a, b) result(c)
        type(jet_t), intent(in) :: a
        real(wp), intent(in) :: b
        type(jet_t) :: c
        c = jet_t(a%f0 / b, a%f1 / b, a%f2 / b)
    end function div_jr

    elemental function div_rj(a, b) result(c)
        real(wp), intent(in) :: a
        type(jet_t), intent(in) :: b
        type(jet_t) :: c
        c = div_jj(lift(a), b)
    end function div_rj

    !> a**n: (a^n)' = n a^(n−1) a', (a^n)'' = n a^(n−1) a'' + n (n−1) a^(n−2) a'².
    elemental function pow_ji(a, n) result(c)
        type(jet_t), intent(in) :: a
        integer, intent(in) :: n
        type(jet_t) :: c
        select case (n)
        case (0)
            c = jet_t(1.0_wp, 0.0_wp, 0.0_wp)
        case (1)
            c = a
        case default
            c%f0 = a%f0**n
            c%f1 = n * a%f0**(n - 1) * a%f1
            c%f2 = n * a%f0**(n - 1) * a%f2 + n * (n - 1) * a%f0**(n - 2) * a%f1**2
        end select
    end function pow_ji

    !> c² = a: c' = a'/(2c), c'' = (a'' − 2 c'²)/(2c).
    elemental function sqrt_j(a) result(c)
        type(jet_t), intent(in) :: a
        type(jet_t) :: c
        c%f0 = sqrt(a%f0)
        c%f1 = a%f1 / (2.0_wp * c%f0)
        c%f2 = (a%f2 - 2.0_wp * c%f1**2) / (2.0_wp * c%f0)
    end function sqrt_j

    elemental function sin_j(a) result(c)
        type(jet_t), intent(in) :: a
        type(jet_t) :: c
        real(wp) :: s, co
        s = sin(a%f0)
        co = cos(a%f0)
        c = jet_t(s, co * a%f1, co * a%f2 - s * a%f1**2)
    end function sin_j

    elemental function cos_j(a) result(c)
        type(jet_t), intent(in) :: a
        type(jet_t) :: c
        real(wp) :: s, co
        s = sin(a%f0)
        co = cos(a%f0)
        c = jet_t(co, -s * a%f1, -s * a%f2 - co * a%f1**2)
    end function cos_j

    pure function matvec_jj(a, x) result(y)
        type(jet_t), intent(in) :: a(:, :), x(:)
        type(jet_t) :: y(size(a, 1))
        integer :: j
        y = 0.0_wp
        do j = 1, size(a, 2)
            y = y + a(:, j) * x(j)
        end do
    end function matvec_jj

    !> A constant jet.
    elemental function lift(x) result(a)
        real(wp), intent(in) :: x
        type(jet_t) :: a
        a = jet_t(x, 0.0_wp, 0.0_wp)
    end function lift

    ! Mixed real and jet products go through the jet ones (a few extra flops
    ! in the γ pass only).
    pure function matvec_jr(a, x) result(y)
        type(jet_t), intent(in) :: a(:, :)
        real(wp), intent(in) :: x(:)
        type(jet_t) :: y(size(a, 1))
        y = matvec_jj(a, lift(x))
    end function matvec_jr

    pure function matvec_rj(a, x) result(y)
        real(wp), intent(in) :: a(:, :)
        type(jet_t), intent(in) :: x(:)
        type(jet_t) :: y(size(a, 1))
        y = matvec_jj(lift(a), x)
    end function matvec_rj

    pure function matmat_jj(a, b) result(c)
        type(jet_t), intent(in) :: a(:, :), b(:, :)
        type(jet_t) :: c(size(a, 1), size(b, 2))
        integer :: j
        do j = 1, size(b, 2)
            c(:, j) = matvec_jj(a, b(:, j))
        end do
    end function matmat_jj

    pure function matmat_jr(a, b) result(c)
        type(jet_t), intent(in) :: a(:, :)
        real(wp), intent(in) :: b(:, :)
        type(jet_t) :: c(size(a, 1), size(b, 2))
        c = matmat_jj(a, lift(b))
    end function matmat_jr

    pure function matmat_rj(a, b) result(c)
        real(wp), intent(in) :: a(:, :)
        type(jet_t), intent(in) :: b(:, :)
        type(jet_t) :: c(size(a, 1), size(b, 2))
        c = matmat_jj(lift(a), b)
    end function matmat_rj
end module flexmbs_mbs_jet
