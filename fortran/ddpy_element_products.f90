!> Dense products of the element kernels that must not be inlined into them: inside the
!> large element routines gfortran 12 spills the vector sums of these loops to memory, or
!> rearranges them into scalar code (up to 2.5 times the instructions), while compiled on
!> their own they keep every sum in a register. A module of its own, since gfortran inlines
!> within a module but not across modules (no link-time optimization here).
module ddpy_element_products
  use ddpy_kinds, only: wp
  implicit none
  private
  public :: lower_product

contains

  !> The lower triangle of k + l r^T + l0 r0^T (k, l, r: 24 x 24, 24 x 48, 24 x 48; some
  !> entries of the strict upper triangle get their values too, and are overwritten by
  !> mirror). In three bands of 8 rows, each with the columns up to its last row, 4 columns
  !> at a time: fixed lengths that the compiler unrolls into eight vector sums kept in
  !> registers over the 49 terms (a triangular loop of varying length would not be), and 96
  !> of the 144 column pieces of 4 rows of the full square.
  pure subroutine lower_product(l, r, l0, r0, k)
    real(wp), intent(in) :: l(24, 48), r(24, 48), l0(24), r0(24)
    real(wp), intent(inout) :: k(24, 24)
    real(wp) :: k1(8), k2(8), k3(8), k4(8)
    integer :: i0, j, q
    do i0 = 0, 16, 8
      do j = 1, i0 + 8, 4
        ! Zero starts: started from the l0 r0^T terms, the loop is no longer vectorized by
        ! columns.
        k1 = 0.0_wp
        k2 = 0.0_wp
        k3 = 0.0_wp
        k4 = 0.0_wp
        do q = 1, 48
          k1 = k1 + l(i0 + 1:i0 + 8, q)*r(j, q)
          k2 = k2 + l(i0 + 1:i0 + 8, q)*r(j + 1, q)
          k3 = k3 + l(i0 + 1:i0 + 8, q)*r(j + 2, q)
          k4 = k4 + l(i0 + 1:i0 + 8, q)*r(j + 3, q)
        end do
        k(i0 + 1:i0 + 8, j) = k(i0 + 1:i0 + 8, j) + k1 + l0(i0 + 1:i0 + 8)*r0(j)
        k(i0 + 1:i0 + 8, j + 1) = k(i0 + 1:i0 + 8, j + 1) + k2 + l0(i0 + 1:i0 + 8)*r0(j + 1)
        k(i0 + 1:i0 + 8, j + 2) = k(i0 + 1:i0 + 8, j + 2) + k3 + l0(i0 + 1:i0 + 8)*r0(j + 2)
        k(i0 + 1:i0 + 8, j + 3) = k(i0 + 1:i0 + 8, j + 3) + k4 + l0(i0 + 1:i0 + 8)*r0(j + 3)
      end do
    end do
  end subroutine lower_product

end module ddpy_element_products
