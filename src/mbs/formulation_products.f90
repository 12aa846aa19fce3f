!> The products with G and M that the formulation's residual, Jacobian and
!> projection share: G(t, q) evaluated once, then G x, Gᵀ x, M x and G v + g_I.
submodule (flexmbs_mbs_formulation) flexmbs_mbs_formulation_products
    implicit none

contains

    module procedure velocity_constraint
        call self%mechanical%constraint_time_derivative(t, q, self%ct, status)
        call g_times(self, v, c)
        c = c + self%ct
    end procedure velocity_constraint

    module procedure eval_g
        if (self%sparse) then
            call self%sp%constraint_jacobian(self%mechanical, t, q, status)
        else
            call self%mechanical%constraint_jacobian(t, q, self%gmat, status)
        end if
    end procedure eval_g

    module procedure g_times
        if (self%sparse) then
            call self%sp%g_times(x, y)
        else
            y = matmul(self%gmat, x)
        end if
    end procedure g_times

    module procedure gt_times
        if (self%sparse) then
            call self%sp%gt_times(x, y)
        else
            y = matmul(x, self%gmat)
        end if
    end procedure gt_times

    module procedure mass_times
        if (self%sparse) then
            call self%sp%m_times(self%mechanical, t, q, x, y, status)
        else
            call self%mechanical%mass(t, q, self%m, status)
            y = matmul(self%m, x)
        end if
    end procedure mass_times
end submodule flexmbs_mbs_formulation_products
