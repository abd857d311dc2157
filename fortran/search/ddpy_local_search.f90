!> Local contact search: orthogonal projection of a point on one patch (paper Eq. 8).
!>
!> Newton-Raphson on the stationarity of 1/2 |S(alpha) - x|^2, with the full Hessian
!> S_,a . S_,b + r . S_,ab (Gauss-Newton where that is not positive definite, i.e. beyond the
!> centre of curvature). The iterate stays in the patch domain: a constraint whose bound is
!> reached and that the gradient pushes against becomes active and the step is taken along
!> the remaining free direction, so points near edges and corners converge to the constrained
!> closest point. The projection is "inside" when no constraint is active at the solution.
module ddpy_local_search
  use ddpy_kinds, only: wp
  use ddpy_surface, only: patch_evaluate, project_to_domain, unit_normal
  implicit none
  private
  public :: project_point

contains

  !> Outward normals c and bounds b of the domain constraints c . alpha <= b.
  pure subroutine domain_constraints(triangle, c, b, m)
    logical, intent(in) :: triangle
    real(wp), intent(out) :: c(2, 4), b(4)
    integer, intent(out) :: m
    c = 0.0_wp; b = 0.0_wp
    if (triangle) then
      m = 3
      c(:, 1) = [0.0_wp, -1.0_wp]                   ! t >= 0
      c(:, 2) = [1.0_wp, 0.0_wp]; b(2) = 1.0_wp      ! s <= 1
      c(:, 3) = [-1.0_wp, 1.0_wp]/sqrt(2.0_wp)      ! t <= s
    else
      m = 4
      c(:, 1) = [-1.0_wp, 0.0_wp]                   ! s >= 0
      c(:, 2) = [1.0_wp, 0.0_wp]; b(2) = 1.0_wp      ! s <= 1
      c(:, 3) = [0.0_wp, -1.0_wp]                   ! t >= 0
      c(:, 4) = [0.0_wp, 1.0_wp]; b(4) = 1.0_wp      ! t <= 1
    end if
  end subroutine domain_constraints

  !> Closest point of patch (coef) to x, started from alpha = start.
  !> On return: alpha, the point S(alpha), the tangents d1 = S_,a, the unit normal, the signed
  !> normal distance (x - S) . n, whether the solution is inside the domain, the iterations
  !> used and whether the iteration converged.
  pure subroutine project_point(kind, stride, coef, degrees, triangle, x, start, &
                                max_iterations, tol, alpha, point, d1, normal, distance, &
                                inside, iterations, converged)
    integer, intent(in) :: kind, stride, degrees(2), max_iterations
    real(wp), intent(in) :: coef(stride), x(3), start(2), tol
    logical, intent(in) :: triangle
    real(wp), intent(out) :: alpha(2), point(3), d1(3, 2), normal(3), distance
    logical, intent(out) :: inside, converged
    integer, intent(out) :: iterations
    real(wp) :: d2(3, 3), r(3), g(2), h(2, 2), step(2), c(2, 4), b(4), e(2), curvature, det
    real(wp) :: trial(2), scale
    integer :: m, nactive, active(4), it
    call domain_constraints(triangle, c, b, m)
    alpha = start
    call project_to_domain(triangle, alpha(1), alpha(2))
    converged = .false.
    iterations = 0
    do it = 1, max_iterations
      iterations = it
      call patch_evaluate(kind, stride, coef, degrees, alpha(1), alpha(2), point, d1, d2)
      r = point - x
      g = [dot_product(r, d1(:, 1)), dot_product(r, d1(:, 2))]
      h(1, 1) = dot_product(d1(:, 1), d1(:, 1)) + dot_product(r, d2(:, 1))
      h(1, 2) = dot_product(d1(:, 1), d1(:, 2)) + dot_product(r, d2(:, 2))
      h(2, 2) = dot_product(d1(:, 2), d1(:, 2)) + dot_product(r, d2(:, 3))
      h(2, 1) = h(1, 2)
      if (h(1, 1) <= 0.0_wp .or. h(1, 1)*h(2, 2) - h(1, 2)**2 <= 0.0_wp) then
        h(1, 1) = dot_product(d1(:, 1), d1(:, 1))
        h(1, 2) = dot_product(d1(:, 1), d1(:, 2))
        h(2, 2) = dot_product(d1(:, 2), d1(:, 2))
        h(2, 1) = h(1, 2)
      end if
      scale = norm2(r)*max(norm2(d1(:, 1)), norm2(d1(:, 2)))
      call find_active(alpha, g, scale, c, b, m, active, nactive)
      select case (nactive)
      case (0)
        det = h(1, 1)*h(2, 2) - h(1, 2)**2
        if (det <= 0.0_wp) exit   ! singular patch point: stop where we are
        step(1) = -(h(2, 2)*g(1) - h(1, 2)*g(2))/det
        step(2) = -(h(1, 1)*g(2) - h(2, 1)*g(1))/det
      case (1)
        e = [-c(2, active(1)), c(1, active(1))]
        curvature = dot_product(e, matmul(h, e))
        if (curvature <= 0.0_wp) exit
        step = -dot_product(e, g)/curvature*e
      case default
        converged = .true.        ! held in a corner of the domain
        exit
      end select
      ! Keep Newton steps local: the start comes from a grid that resolves the patch.
      if (maxval(abs(step)) > 0.5_wp) step = step*(0.5_wp/maxval(abs(step)))
      trial = alpha + step
      call project_to_domain(triangle, trial(1), trial(2))
      step = trial - alpha
      alpha = trial
      if (maxval(abs(step)) <= tol) then
        converged = .true.
        exit
      end if
    end do
    call patch_evaluate(kind, stride, coef, degrees, alpha(1), alpha(2), point, d1, d2)
    r = point - x
    g = [dot_product(r, d1(:, 1)), dot_product(r, d1(:, 2))]
    scale = norm2(r)*max(norm2(d1(:, 1)), norm2(d1(:, 2)))
    call find_active(alpha, g, scale, c, b, m, active, nactive)
    inside = nactive == 0
    normal = unit_normal(d1)
    distance = dot_product(x - point, normal)
  end subroutine project_point

  !> Constraints at their bound that the descent direction -g pushes against. A push
  !> below a relative 1e-10 of |r| |S_,a| is rounding: a point exactly on an edge is inside.
  pure subroutine find_active(alpha, g, scale, c, b, m, active, nactive)
    real(wp), intent(in) :: alpha(2), g(2), scale, c(2, 4), b(4)
    integer, intent(in) :: m
    integer, intent(out) :: active(4), nactive
    integer :: i
    nactive = 0
    active = 0
    do i = 1, m
      if (dot_product(c(:, i), alpha) >= b(i) - 1.0e-12_wp .and. &
          -dot_product(c(:, i), g) > 1.0e-10_wp*scale) then
        nactive = nactive + 1
        active(nactive) = i
      end if
    end do
  end subroutine find_active

end module ddpy_local_search
