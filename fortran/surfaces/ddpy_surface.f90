!> Batched evaluation of tool surfaces over many (patch, parameter) pairs, parallel with OpenMP.
!>
!> Bezier and Nagata patches answer the same questions (point, derivatives, unit normal); this
!> module is the one place that loops over query points, so the contact search can reuse it.
module ddpy_surface
  use ddpy_kinds, only: wp
  use ddpy_bezier, only: max_bezier_degree, bezier_evaluate
  use ddpy_nagata, only: nagata_evaluate, nagata_coefficient_count
  implicit none
  private
  public :: unit_normal, bezier_evaluate_batch, nagata_evaluate_batch, patch_evaluate, &
            project_to_domain, surface_bezier, surface_nagata, bezier_stride, nagata_stride

  !> Kinds of surface, and the number of reals per patch in their coefficient arrays.
  integer, parameter :: surface_bezier = 1, surface_nagata = 2
  integer, parameter :: bezier_stride = 3*(max_bezier_degree + 1)**2
  integer, parameter :: nagata_stride = 3*nagata_coefficient_count

  integer, parameter :: nb = max_bezier_degree

contains

  !> unit(S_,1 x S_,2); the zero vector where the tangents are parallel (singular point).
  pure function unit_normal(d1) result(n)
    real(wp), intent(in) :: d1(3, 2)
    real(wp) :: n(3), length
    n(1) = d1(2, 1)*d1(3, 2) - d1(3, 1)*d1(2, 2)
    n(2) = d1(3, 1)*d1(1, 2) - d1(1, 1)*d1(3, 2)
    n(3) = d1(1, 1)*d1(2, 2) - d1(2, 1)*d1(1, 2)
    length = norm2(n)
    if (length > 0.0_wp) then
      n = n/length
    else
      n = 0.0_wp
    end if
  end function unit_normal

  !> Point and derivatives of one patch of either kind. coef holds that patch's coefficients
  !> (bezier_stride or nagata_stride reals); degrees is only read for Bezier patches.
  pure subroutine patch_evaluate(kind, stride, coef, degrees, s, t, point, d1, d2)
    integer, intent(in) :: kind, stride, degrees(2)
    real(wp), intent(in) :: coef(stride), s, t
    real(wp), intent(out) :: point(3), d1(3, 2), d2(3, 3)
    if (kind == surface_bezier) then
      call bezier_evaluate(degrees(1), degrees(2), coef, s, t, point, d1, d2)
    else
      call nagata_evaluate(coef, s, t, point, d1, d2)
    end if
  end subroutine patch_evaluate

  !> Euclidean projection of (s, t) onto the patch domain: [0,1]^2, or the triangle
  !> 0 <= t <= s <= 1 when triangle is true.
  pure subroutine project_to_domain(triangle, s, t)
    logical, intent(in) :: triangle
    real(wp), intent(inout) :: s, t
    real(wp) :: candidates(2, 3), best, d, m
    integer :: i, nearest
    if (.not. triangle) then
      s = min(max(s, 0.0_wp), 1.0_wp)
      t = min(max(t, 0.0_wp), 1.0_wp)
      return
    end if
    if (t >= 0.0_wp .and. s <= 1.0_wp .and. t <= s) return
    ! Nearest point of each edge: t = 0, s = 1 and the diagonal t = s.
    candidates(:, 1) = [min(max(s, 0.0_wp), 1.0_wp), 0.0_wp]
    candidates(:, 2) = [1.0_wp, min(max(t, 0.0_wp), 1.0_wp)]
    m = min(max(0.5_wp*(s + t), 0.0_wp), 1.0_wp)
    candidates(:, 3) = [m, m]
    best = huge(1.0_wp)
    nearest = 1
    do i = 1, 3
      d = (candidates(1, i) - s)**2 + (candidates(2, i) - t)**2
      if (d < best) then
        best = d
        nearest = i
      end if
    end do
    s = candidates(1, nearest)
    t = candidates(2, nearest)
  end subroutine project_to_domain

  !> Evaluate Bezier patches at k points; patch(i) is 1-based. info = 0, or the first point
  !> whose patch index is out of range (nothing is evaluated for it).
  subroutine bezier_evaluate_batch(npatch, degrees, coef, k, patch, params, points, derivs, &
                                   normals, second, info)
    integer, intent(in) :: npatch, k
    integer, intent(in) :: degrees(2, npatch), patch(k)
    real(wp), intent(in) :: coef(3, 0:nb, 0:nb, npatch), params(2, k)
    real(wp), intent(out) :: points(3, k), derivs(3, 2, k), normals(3, k), second(3, 3, k)
    integer, intent(out) :: info
    integer :: i, p, bad
    bad = huge(0)
    !$omp parallel do schedule(static) private(p) reduction(min:bad) if(k > 512)
    do i = 1, k
      p = patch(i)
      if (p < 1 .or. p > npatch) then
        bad = min(bad, i)
        points(:, i) = 0.0_wp; derivs(:, :, i) = 0.0_wp; normals(:, i) = 0.0_wp
        second(:, :, i) = 0.0_wp
        cycle
      end if
      call bezier_evaluate(degrees(1, p), degrees(2, p), coef(:, :, :, p), params(1, i), &
                           params(2, i), points(:, i), derivs(:, :, i), second(:, :, i))
      normals(:, i) = unit_normal(derivs(:, :, i))
    end do
    !$omp end parallel do
    info = merge(0, bad, bad == huge(0))
  end subroutine bezier_evaluate_batch

  !> Evaluate Nagata patches (or facets) at k points; same conventions as the Bezier batch.
  subroutine nagata_evaluate_batch(npatch, coef, k, patch, params, points, derivs, normals, &
                                   second, info)
    integer, intent(in) :: npatch, k
    integer, intent(in) :: patch(k)
    real(wp), intent(in) :: coef(3, nagata_coefficient_count, npatch), params(2, k)
    real(wp), intent(out) :: points(3, k), derivs(3, 2, k), normals(3, k), second(3, 3, k)
    integer, intent(out) :: info
    integer :: i, p, bad
    bad = huge(0)
    !$omp parallel do schedule(static) private(p) reduction(min:bad) if(k > 512)
    do i = 1, k
      p = patch(i)
      if (p < 1 .or. p > npatch) then
        bad = min(bad, i)
        points(:, i) = 0.0_wp; derivs(:, :, i) = 0.0_wp; normals(:, i) = 0.0_wp
        second(:, :, i) = 0.0_wp
        cycle
      end if
      call nagata_evaluate(coef(:, :, p), params(1, i), params(2, i), points(:, i), &
                           derivs(:, :, i), second(:, :, i))
      normals(:, i) = unit_normal(derivs(:, :, i))
    end do
    !$omp end parallel do
    info = merge(0, bad, bad == huge(0))
  end subroutine nagata_evaluate_batch

end module ddpy_surface
