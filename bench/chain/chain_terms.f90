!> `flexmbs-bench-chain`: the cost of a rigid chain's terms per evaluation,
!> as a formulation calls them on every Newton Jacobian — M(q), f(q, v),
!> ∂(M w)/∂q and ∂f/∂(q, v) — for serial chains of 4, 8, 16, 32 and 64
!> links (revolute joints, axes turning from link to link). Prints per size
!> the time per evaluation of each term and of all four (best of several
!> repetitions, CPU time), the ratio per doubling and its exponent p
!> (t ~ n^p); for comparison the forward differences the analytic
!> derivatives replaced (mechanical_problem_t's defaults: n + 1 evaluations
!> of M, 2n + 1 of f). Never asserts: a benchmark.
program flexmbs_bench_chain
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_status, only: status_t
    use flexmbs_dae_mechanical_problem, only: difference_step
    use flexmbs_mbs_rigid_chain, only: rigid_chain_t, new_rigid_chain, chain_body_t, &
        chain_joint_revolute
    implicit none
    integer, parameter :: sizes(5) = [4, 8, 16, 32, 64]
    ! best of `repeats` timings, each at least `min_seconds` long
    integer, parameter :: repeats = 5
    real(wp), parameter :: min_seconds = 0.05_wp
    integer, parameter :: nterms = 7
    real(wp) :: times(nterms, size(sizes))
    integer :: k, term
    character(len=*), parameter :: names(nterms) = ['M(q)         ', 'f(q, v)      ', &
        'd(M w)/dq    ', 'df/d(q, v)   ', 'all four     ', 'd(M w)/dq fd ', 'df/d(q, v) fd']
    print '(a)', 'chain terms per evaluation: links, then seconds per call of M(q), f(q, v), ' // &
        'd(M w)/dq, df/d(q, v), all four, and the forward differences of d(M w)/dq and ' // &
        'df/d(q, v) (best of 5, CPU)'
    do k = 1, size(sizes)
        call time_chain(sizes(k), times(:, k))
        print '(a,i4,7es11.3)', 'chain_terms', sizes(k), times(:, k)
    end do
    print '(a)', 'growth per doubling of the links: ratio and exponent p (t ~ n^p)'
    do term = 1, nterms
        do k = 2, size(sizes)
            print '(a,a,i3,a,i3,a,f7.2,a,f5.2)', 'chain_growth ', names(term), sizes(k - 1), &
                ' ->', sizes(k), ': ratio', times(term, k) / times(term, k - 1), ', p =', &
                log(times(term, k) / times(term, k - 1)) / log(2.0_wp)
        end do
    end do

contains

    !> Seconds per call of each term for a chain of n links.
    subroutine time_chain(n, t)
        integer, intent(in) :: n
        real(wp), intent(out) :: t(nterms)
        type(rigid_chain_t) :: chain
        type(chain_body_t) :: b(n)
        type(status_t) :: status
        real(wp) :: q(n), v(n), w(n), m(n, n), f(n), mq(n, n), fq(n, n), fv(n, n), axis(3), &
            start, finish
        integer :: i, term, r, calls, c
        do i = 1, n
            axis = [sin(1.7_wp * i), cos(1.7_wp * i), 0.6_wp]
            b(i)%parent = i - 1
            b(i)%joint = chain_joint_revolute
            b(i)%joint_position = [merge(0.0_wp, 0.3_wp, i == 1), 0.0_wp, 0.0_wp]
            b(i)%axis = axis / norm2(axis)
            b(i)%centre = [0.15_wp, 0.01_wp, 0.0_wp]
            b(i)%mass = 0.5_wp
            b(i)%inertia = reshape([0.02_wp, 0.0_wp, 0.0_wp, 0.0_wp, 0.03_wp, 0.0_wp, &
                                    0.0_wp, 0.0_wp, 0.025_wp], [3, 3])
            q(i) = 0.3_wp * sin(0.9_wp * i)
            v(i) = 0.5_wp * cos(1.3_wp * i)
            w(i) = cos(0.7_wp * i)
        end do
        chain = new_rigid_chain(b, status, gravity=[0.0_wp, 0.0_wp, -9.81_wp])
        if (.not. status%ok()) error stop 'flexmbs-bench-chain: ' // status%text()
        do term = 1, nterms
            t(term) = huge(1.0_wp)
            calls = 1
            ! best over `repeats` of the mean time per call
            do r = 1, repeats
                do
                    call cpu_time(start)
                    do c = 1, calls
                        call evaluate(chain, term, q, v, w, m, f, mq, fq, fv)
                    end do
                    call cpu_time(finish)
                    if (finish - start >= min_seconds) exit
                    calls = 2 * calls
                end do
                t(term) = min(t(term), (finish - start) / calls)
            end do
        end do
    end subroutine time_chain

    !> Term `term` (5: all four; 6, 7: the differences) of the chain at
    !> (q, v), M acting on w.
    subroutine evaluate(chain, term, q, v, w, m, f, mq, fq, fv)
        type(rigid_chain_t), intent(inout) :: chain
        integer, intent(in) :: term
        real(wp), intent(in) :: q(:), v(:), w(:)
        real(wp), intent(out) :: m(:, :), f(:), mq(:, :), fq(:, :), fv(:, :)
        type(status_t) :: status
        if (term == 1 .or. term == 5) call chain%mass(0.0_wp, q, m, status)
        if (term == 2 .or. term == 5) call chain%forces(0.0_wp, q, v, f, status)
        if (term == 3 .or. term == 5) call chain%mass_derivative(0.0_wp, q, w, mq, status)
        if (term == 4 .or. term == 5) call chain%force_derivatives(0.0_wp, q, v, fq, fv, status)
        if (term == 6) call difference_mass_derivative(chain, q, w, m, mq)
        if (term == 7) call difference_force_derivatives(chain, q, v, f, fq, fv)
    end subroutine evaluate

    !> ∂(M w)/∂q by forward differences, as mechanical_problem_t's default
    !> (n + 1 evaluations of M; m is scratch).
    subroutine difference_mass_derivative(chain, q, w, m, mq)
        type(rigid_chain_t), intent(inout) :: chain
        real(wp), intent(in) :: q(:), w(:)
        real(wp), intent(out) :: m(:, :), mq(:, :)
        real(wp) :: qp(size(q)), base(size(w)), h
        type(status_t) :: status
        integer :: j
        call chain%mass(0.0_wp, q, m, status)
        base = matmul(m, w)
        qp = q
        do j = 1, size(q)
            h = difference_step(q(j))
            qp(j) = q(j) + h
            call chain%mass(0.0_wp, qp, m, status)
            mq(:, j) = (matmul(m, w) - base) / h
            qp(j) = q(j)
        end do
    end subroutine difference_mass_derivative

    !> ∂f/∂q and ∂f/∂v by forward differences, as mechanical_problem_t's
    !> default (2n + 1 evaluations of f; f is scratch).
    subroutine difference_force_derivatives(chain, q, v, f, fq, fv)
        type(rigid_chain_t), intent(inout) :: chain
        real(wp), intent(in) :: q(:), v(:)
        real(wp), intent(out) :: f(:), fq(:, :), fv(:, :)
        real(wp) :: qp(size(q)), vp(size(v)), base(size(v)), h
        type(status_t) :: status
        integer :: j
        call chain%forces(0.0_wp, q, v, base, status)
        ! columns 1 .. nq along q, then along v
        do j = 1, size(q) + size(v)
            qp = q
            vp = v
            if (j <= size(q)) then
                h = difference_step(q(j))
                qp(j) = q(j) + h
            else
                h = difference_step(v(j - size(q)))
                vp(j - size(q)) = v(j - size(q)) + h
            end if
            call chain%forces(0.0_wp, qp, vp, f, status)
            if (j <= size(q)) then
                fq(:, j) = (f - base) / h
            else
                fv(:, j - size(q)) = (f - base) / h
            end if
        end do
    end subroutine difference_force_derivatives
end program flexmbs_bench_chain
