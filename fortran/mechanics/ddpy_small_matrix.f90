!> Small dense matrices of the element kernels, written out: the product of 3 x 3 matrices,
!> the symmetric tensor of a Voigt stress, the Voigt strain map of a change of basis (the
!> strain rotation into the material axes) and a Voigt vector times the strain-displacement
!> rows. One copy for the hexahedron and the solid-shell (ddpy_hex8, ddpy_solid_shell),
!> called from their element loops without link-time optimization: their answers are
!> bitwise those of the copies each module had (the built-in case's run, every increment
!> and field), and the time per Newton iteration the same within its noise
!> (docs/theory/speed.md). The determinant and inverse (ddpy_det_inverse3.inc) and the
!> materials' helpers (ddpy_material_helpers.inc) are included into each module that uses
!> them instead: from here (with link-time optimization too) they moved the answers in the
!> last bits, which the Newton loop carried to 3e-9 of the tool forces and 1e-7 of the
!> strains.
!> Voigt order 11, 22, 33, 12, 23, 31 with engineering shear strains throughout.
module ddpy_small_matrix
  use ddpy_kinds, only: wp
  implicit none
  private
  public :: product3, stress_tensor, strain_map, by_dofs

  !> Index pairs (i, j) of the Voigt components.
  integer, parameter :: voigt(2, 6) = reshape([1, 1, 2, 2, 3, 3, 1, 2, 2, 3, 3, 1], [2, 6])

contains

  !> The product of two 3 x 3 matrices, written out (gfortran calls its library for some
  !> matmul forms, which costs more than the product).
  pure function product3(a, b) result(c)
    real(wp), intent(in) :: a(3, 3), b(3, 3)
    real(wp) :: c(3, 3)
    integer :: j
    do j = 1, 3
      c(:, j) = a(:, 1)*b(1, j) + a(:, 2)*b(2, j) + a(:, 3)*b(3, j)
    end do
  end function product3

  !> The symmetric 3 x 3 tensor of a Voigt stress.
  pure function stress_tensor(s) result(t)
    real(wp), intent(in) :: s(6)
    real(wp) :: t(3, 3)
    t(:, 1) = [s(1), s(4), s(6)]
    t(:, 2) = [s(4), s(2), s(5)]
    t(:, 3) = [s(6), s(5), s(3)]
  end function stress_tensor

  !> Voigt strain map t (engineering shears) from the basis whose dual rows are the rows
  !> of axes: strain(r) of the components axes(k, i) axes(l, j) E_kl. With the columns of
  !> axes the material axes (orthonormal) it turns global strains into material ones,
  !> strain_material = t strain_global (the stress goes back as t^T stress_material, the
  !> tangent as t^T D t); with axes = J^-1 (rows: dxi_a/dx) it turns covariant natural
  !> strains into Cartesian ones. A subroutine (no result descriptor), by blocks of rows
  !> and columns (normal, shear) without branches.
  pure subroutine strain_map(axes, t)
    real(wp), intent(in) :: axes(3, 3)
    real(wp), intent(out) :: t(6, 6)
    integer :: r, c, i, j, k, l
    do c = 1, 3
      do r = 1, 3
        t(r, c) = axes(c, r)*axes(c, r)
      end do
      do r = 4, 6
        i = voigt(1, r)
        j = voigt(2, r)
        t(r, c) = 2.0_wp*axes(c, i)*axes(c, j)
      end do
    end do
    do c = 4, 6
      k = voigt(1, c)
      l = voigt(2, c)
      do r = 1, 3
        t(r, c) = axes(k, r)*axes(l, r)
      end do
      do r = 4, 6
        i = voigt(1, r)
        j = voigt(2, r)
        t(r, c) = axes(k, i)*axes(l, j) + axes(l, i)*axes(k, j)
      end do
    end do
  end subroutine strain_map

  !> sum_r bt(:, r) v(r): a Voigt row vector v times b, over the 24 dofs.
  pure function by_dofs(bt, v) result(w)
    real(wp), intent(in) :: bt(24, 6), v(6)
    real(wp) :: w(24)
    w = bt(:, 1)*v(1) + bt(:, 2)*v(2) + bt(:, 3)*v(3) + bt(:, 4)*v(4) + bt(:, 5)*v(5) &
        + bt(:, 6)*v(6)
  end function by_dofs

end module ddpy_small_matrix
