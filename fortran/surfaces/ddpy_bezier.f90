!> Tensor-product Bezier patches of degree <= 6 in each direction, stored in power basis.
!>
!> The power (monomial) basis is evaluated with nested Horner schemes, which is cheaper than
!> Bernstein or de Casteljau evaluation (paper, "Bezier patches"). The monomials are taken about
!> the patch centre, (u - 1/2)^k (v - 1/2)^l: the coefficients of the Bernstein polynomials are
!> then at most C(n, i) in sum instead of growing like 4^n, which keeps the rounding of a degree
!> 6 x 6 patch near 1e-14 of its size (about 1e-11 in the plain basis about 0). The degree cap
!> of 6 is the paper's; de Casteljau is kept as an independent cross-check.
module ddpy_bezier
  use ddpy_kinds, only: wp
  implicit none
  private
  public :: max_bezier_degree, binomial, bernstein_to_power_matrix, bezier_power_coefficients, &
            bezier_evaluate, bezier_de_casteljau

  integer, parameter :: max_bezier_degree = 6

contains

  !> Binomial coefficient C(n, k), 0 <= k <= n.
  pure function binomial(n, k) result(c)
    integer, intent(in) :: n, k
    real(wp) :: c
    integer :: i
    c = 1.0_wp
    do i = 1, k
      c = c*real(n - k + i, wp)/real(i, wp)
    end do
  end function binomial

  !> M(k, i): B_i^n(1/2 + t) = C(n,i) (1/2 + t)^i (1/2 - t)^(n-i) = sum_k M(k, i) t^k.
  pure subroutine bernstein_to_power_matrix(n, m)
    integer, intent(in) :: n
    real(wp), intent(out) :: m(0:n, 0:n)
    real(wp) :: poly(0:n)
    integer :: i, j, d
    do i = 0, n
      ! Multiply out (1/2 + t)^i (1/2 - t)^(n-i), one factor at a time.
      poly = 0.0_wp
      poly(0) = 1.0_wp
      d = 0
      do j = 1, n
        d = d + 1
        if (j <= i) then
          poly(1:d) = 0.5_wp*poly(1:d) + poly(0:d - 1)
        else
          poly(1:d) = 0.5_wp*poly(1:d) - poly(0:d - 1)
        end if
        poly(0) = 0.5_wp*poly(0)
      end do
      m(:, i) = binomial(n, i)*poly
    end do
  end subroutine bernstein_to_power_matrix

  !> Centred power-basis coefficients A = M_nu P M_nv^T of one patch, per coordinate:
  !> S(u, v) = sum_kl A_kl (u - 1/2)^k (v - 1/2)^l.
  !> control(:, i, j) is the Bernstein control point P_ij (i along u, j along v).
  pure subroutine bezier_power_coefficients(nu, nv, control, coef)
    integer, intent(in) :: nu, nv
    real(wp), intent(in) :: control(3, 0:max_bezier_degree, 0:max_bezier_degree)
    real(wp), intent(out) :: coef(3, 0:max_bezier_degree, 0:max_bezier_degree)
    real(wp) :: mu(0:nu, 0:nu), mv(0:nv, 0:nv)
    integer :: d
    call bernstein_to_power_matrix(nu, mu)
    call bernstein_to_power_matrix(nv, mv)
    coef = 0.0_wp
    do d = 1, 3
      coef(d, 0:nu, 0:nv) = matmul(mu, matmul(control(d, 0:nu, 0:nv), transpose(mv)))
    end do
  end subroutine bezier_power_coefficients

  !> Point, first and second derivatives of a centred power-basis patch at (u, v).
  !> d1(:, 1) = S_u, d1(:, 2) = S_v; d2(:, 1) = S_uu, d2(:, 2) = S_uv, d2(:, 3) = S_vv.
  pure subroutine bezier_evaluate(nu, nv, coef, u, v, point, d1, d2)
    integer, intent(in) :: nu, nv
    real(wp), intent(in) :: coef(3, 0:max_bezier_degree, 0:max_bezier_degree)
    real(wp), intent(in) :: u, v
    real(wp), intent(out) :: point(3), d1(3, 2), d2(3, 3)
    real(wp) :: s, t
    ! a0, a1, a2: the u-polynomial of each v power and its first and (half) second derivative.
    real(wp) :: a0(3, 0:max_bezier_degree), a1(3, 0:max_bezier_degree), a2(3, 0:max_bezier_degree)
    real(wp) :: s0(3), s1(3), s2(3), t0(3), t1(3), r0(3)
    integer :: k, l
    s = u - 0.5_wp
    t = v - 0.5_wp
    do l = 0, nv
      a0(:, l) = coef(:, nu, l)
      a1(:, l) = 0.0_wp
      a2(:, l) = 0.0_wp
      do k = nu - 1, 0, -1
        a2(:, l) = a2(:, l)*s + a1(:, l)
        a1(:, l) = a1(:, l)*s + a0(:, l)
        a0(:, l) = a0(:, l)*s + coef(:, k, l)
      end do
    end do
    ! Horner in v on a0 (value, d/dv, half d2/dv2), on a1 (value, d/dv) and on a2 (value).
    s0 = a0(:, nv); s1 = 0.0_wp; s2 = 0.0_wp
    t0 = a1(:, nv); t1 = 0.0_wp
    r0 = a2(:, nv)
    do l = nv - 1, 0, -1
      s2 = s2*t + s1
      s1 = s1*t + s0
      s0 = s0*t + a0(:, l)
      t1 = t1*t + t0
      t0 = t0*t + a1(:, l)
      r0 = r0*t + a2(:, l)
    end do
    point = s0
    d1(:, 1) = t0
    d1(:, 2) = s1
    d2(:, 1) = 2.0_wp*r0
    d2(:, 2) = t1
    d2(:, 3) = 2.0_wp*s2
  end subroutine bezier_evaluate

  !> Point of a patch from its Bernstein control net by de Casteljau (cross-check only).
  pure subroutine bezier_de_casteljau(nu, nv, control, u, v, point)
    integer, intent(in) :: nu, nv
    real(wp), intent(in) :: control(3, 0:max_bezier_degree, 0:max_bezier_degree)
    real(wp), intent(in) :: u, v
    real(wp), intent(out) :: point(3)
    real(wp) :: row(3, 0:max_bezier_degree), col(3, 0:max_bezier_degree)
    integer :: i, j, r
    do i = 0, nu
      col(:, 0:nv) = control(:, i, 0:nv)
      do r = 1, nv
        do j = 0, nv - r
          col(:, j) = (1.0_wp - v)*col(:, j) + v*col(:, j + 1)
        end do
      end do
      row(:, i) = col(:, 0)
    end do
    do r = 1, nu
      do i = 0, nu - r
        row(:, i) = (1.0_wp - u)*row(:, i) + u*row(:, i + 1)
      end do
    end do
    point = row(:, 0)
  end subroutine bezier_de_casteljau

end module ddpy_bezier
