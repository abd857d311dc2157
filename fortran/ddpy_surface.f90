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
  public :: unit_normal, bezier_evaluate_batch, nagata_evaluate_batch

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
    !$omp parallel do schedule(static) private(p) reduction(min:bad)
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
    !$omp parallel do schedule(static) private(p) reduction(min:bad)
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
