!> The material's doorway to Python (fortran/ddpy_core.pyf): flat arrays and C-bound
!> procedures, scalars in by value, as in ddpy_api. Nothing here prints or stops.
module ddpy_api_material
  use, intrinsic :: iso_c_binding, only: c_int, c_double
  use ddpy_kinds, only: wp
  use ddpy_material, only: material_prop_count, material_update, material_hardening, &
                           material_check, hill48_from_r_values, yield_landing, &
                           material_yield_stress, material_bad_props
  use ddpy_material_mixed, only: material_update_mixed
  implicit none
  private
  public :: api_material_update, api_material_update_mixed, api_material_hardening, api_material_check, &
            api_hill48_from_r_values, api_yield_landing

  integer, parameter :: np = material_prop_count

contains

  !> Return mapping at k points of one material (OpenMP parallel over the points).
  !> stress_old(:, i), strain_increment(:, i): Voigt (11, 22, 33, 12, 23, 31), engineering
  !> shear strains; tangent(:, :, i) = d stress / d strain_increment; plastic(i) = 1 when the
  !> point yielded; status(i) = 0, or > 0 when its return mapping failed.
  subroutine api_material_update(props, k, stress_old, ep_old, strain_increment, stress, ep, &
                                 tangent, plastic, status) bind(C, name="ddpy_material_update")
    integer(c_int), value, intent(in) :: k
    real(c_double), intent(in) :: props(np), stress_old(6, k), ep_old(k), &
                                  strain_increment(6, k)
    real(c_double), intent(out) :: stress(6, k), ep(k), tangent(6, 6, k)
    integer(c_int), intent(out) :: plastic(k), status(k)
    integer :: i, point_status
    logical :: yielded
    !$omp parallel do schedule(static) private(yielded, point_status) if(k > 256)
    do i = 1, k
      call material_update(props, stress_old(:, i), ep_old(i), strain_increment(:, i), &
                           stress(:, i), ep(i), tangent(:, :, i), yielded, point_status)
      plastic(i) = merge(1_c_int, 0_c_int, yielded)
      status(i) = point_status
    end do
    !$omp end parallel do
  end subroutine api_material_update

  !> Return mapping with mixed isotropic-kinematic hardening at k points of one material
  !> (material_update_mixed; with C_X zero the backstress stays as given, a shifted yield
  !> surface): api_material_update's arguments and the backstress
  !> back_old(:, i) in, back(:, i) out (Voigt, deviatoric).
  subroutine api_material_update_mixed(props, k, stress_old, back_old, ep_old, &
                                       strain_increment, stress, back, ep, tangent, plastic, &
                                       status) bind(C, name="ddpy_material_update_mixed")
    integer(c_int), value, intent(in) :: k
    real(c_double), intent(in) :: props(np), stress_old(6, k), back_old(6, k), ep_old(k), &
                                  strain_increment(6, k)
    real(c_double), intent(out) :: stress(6, k), back(6, k), ep(k), tangent(6, 6, k)
    integer(c_int), intent(out) :: plastic(k), status(k)
    integer :: i, point_status
    logical :: yielded
    real(wp) :: floor
    if (material_check(props) /= 0) then
      stress = stress_old
      back = back_old
      ep = ep_old
      tangent = 0.0_wp
      plastic = 0
      status = material_bad_props
      return
    end if
    floor = material_yield_stress(props, 0.0_wp)
    !$omp parallel do schedule(static) private(yielded, point_status) if(k > 256)
    do i = 1, k
      call material_update_mixed(props, floor, stress_old(:, i), back_old(:, i), ep_old(i), &
                                 strain_increment(:, i), stress(:, i), back(:, i), ep(i), &
                                 tangent(:, :, i), yielded, point_status)
      plastic(i) = merge(1_c_int, 0_c_int, yielded)
      status(i) = point_status
    end do
    !$omp end parallel do
  end subroutine api_material_update_mixed

  !> Yield stress Y(ep) and hardening slope dY/dep at k equivalent plastic strains.
  subroutine api_material_hardening(props, k, ep, y, slope) &
    bind(C, name="ddpy_material_hardening")
    integer(c_int), value, intent(in) :: k
    real(c_double), intent(in) :: props(np), ep(k)
    real(c_double), intent(out) :: y(k), slope(k)
    integer :: i
    do i = 1, k
      call material_hardening(props, ep(i), y(i), slope(i))
    end do
  end subroutine api_material_hardening

  !> info = 0 when the properties are valid, else the 1-based index of the first bad one.
  subroutine api_material_check(props, info) bind(C, name="ddpy_material_check")
    real(c_double), intent(in) :: props(np)
    integer(c_int), intent(out) :: info
    info = material_check(props)
  end subroutine api_material_check

  !> Hill'48 (F, G, H, L, M, N) from r0, r45, r90 (zeros for non-positive r-values).
  subroutine api_hill48_from_r_values(r0, r45, r90, coefficients) &
    bind(C, name="ddpy_hill48_from_r_values")
    real(c_double), value, intent(in) :: r0, r45, r90
    real(c_double), intent(out) :: coefficients(6)
    real(wp) :: hill(6)
    call hill48_from_r_values(r0, r45, r90, hill)
    coefficients = hill
  end subroutine api_hill48_from_r_values

  !> Fraction of an increment at which the first elastic point of k lands on the yield
  !> surface (see yield_landing).
  subroutine api_yield_landing(props, k, stress_old, ep_old, strain_increment, tolerance, &
                               fraction) bind(C, name="ddpy_yield_landing")
    integer(c_int), value, intent(in) :: k
    real(c_double), value, intent(in) :: tolerance
    real(c_double), intent(in) :: props(np), stress_old(6, k), ep_old(k), &
                                  strain_increment(6, k)
    real(c_double), intent(out) :: fraction
    fraction = yield_landing(props, k, stress_old, ep_old, strain_increment, tolerance)
  end subroutine api_yield_landing

end module ddpy_api_material
