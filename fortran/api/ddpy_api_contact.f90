!> f2py doorway of the pointwise contact law (see ddpy_api.f90 for the conventions).
module ddpy_api_contact
  use, intrinsic :: iso_c_binding, only: c_int, c_double
  use ddpy_kinds, only: wp
  use ddpy_contact, only: contact_residual, normal_derivative
  implicit none
  private
  public :: api_contact_residual

contains

  !> Alart-Curnier residual of k nodes with its derivatives; tangents and second
  !> derivatives of the tool at the closest points give the curvature term.
  subroutine api_contact_residual(k, lambda, n, g, tangents, second, v, mu, r, c, dc_dlambda, &
                                  dc_dx, state) bind(C, name="ddpy_contact_residual")
    integer(c_int), value, intent(in) :: k
    real(c_double), intent(in) :: lambda(3, k), n(3, k), g(k), tangents(3, 2, k), &
                                  second(3, 3, k), v(3, k), mu(k), r(k)
    real(c_double), intent(out) :: c(3, k), dc_dlambda(3, 3, k), dc_dx(3, 3, k)
    integer(c_int), intent(out) :: state(k)
    integer :: i
    real(wp) :: dndx(3, 3)
    !$omp parallel do schedule(static) private(dndx) if(k > 256)
    do i = 1, k
      dndx = normal_derivative(tangents(:, :, i), second(:, :, i), n(:, i), g(i))
      call contact_residual(lambda(:, i), n(:, i), g(i), dndx, v(:, i), mu(i), r(i), &
                            c(:, i), dc_dlambda(:, :, i), dc_dx(:, :, i), state(i))
    end do
    !$omp end parallel do
  end subroutine api_contact_residual

end module ddpy_api_contact
