!> Dense products of the element kernels that must not be inlined into them: inside the
!> large element routines gfortran 12 spills the vector sums of these loops to memory, or
!> rearranges them into scalar code (up to 2.5 times the instructions), while compiled on
!> their own they keep every sum in a register. A module of its own, since gfortran inlines
!> within a module but not across modules (no link-time optimization here).
module ddpy_element_products
  use ddpy_kinds, only: wp
  implicit none
  private
  public :: lower_product, subtract_lower_gram, add_congruence, add_congruence_t, &
            add_pair_product

contains

  !> The lower triangle of k = l r^T + l0 r0^T (k, l, r: 24 x 24, 24 x 48, 24 x 48; some
  !> entries of the strict upper triangle get values too, the others are left as they
  !> are). In three bands of 8 rows, each with the columns up to its last row, 4 columns
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
        k(i0 + 1:i0 + 8, j) = k1 + l0(i0 + 1:i0 + 8)*r0(j)
        k(i0 + 1:i0 + 8, j + 1) = k2 + l0(i0 + 1:i0 + 8)*r0(j + 1)
        k(i0 + 1:i0 + 8, j + 2) = k3 + l0(i0 + 1:i0 + 8)*r0(j + 2)
        k(i0 + 1:i0 + 8, j + 3) = k4 + l0(i0 + 1:i0 + 8)*r0(j + 3)
      end do
    end do
  end subroutine lower_product

  !> The lower triangle of k = k - y y^T (k: 24 x 24, y: 24 x 13; some entries of the
  !> strict upper triangle change too): the static condensation of the solid-shell's 13
  !> enhanced parameters, in the bands of lower_product.
  pure subroutine subtract_lower_gram(y, k)
    real(wp), intent(in) :: y(24, 13)
    real(wp), intent(inout) :: k(24, 24)
    real(wp) :: k1(8), k2(8), k3(8), k4(8)
    integer :: i0, j, q
    do i0 = 0, 16, 8
      do j = 1, i0 + 8, 4
        k1 = 0.0_wp
        k2 = 0.0_wp
        k3 = 0.0_wp
        k4 = 0.0_wp
        do q = 1, 13
          k1 = k1 + y(i0 + 1:i0 + 8, q)*y(j, q)
          k2 = k2 + y(i0 + 1:i0 + 8, q)*y(j + 1, q)
          k3 = k3 + y(i0 + 1:i0 + 8, q)*y(j + 2, q)
          k4 = k4 + y(i0 + 1:i0 + 8, q)*y(j + 3, q)
        end do
        k(i0 + 1:i0 + 8, j) = k(i0 + 1:i0 + 8, j) - k1
        k(i0 + 1:i0 + 8, j + 1) = k(i0 + 1:i0 + 8, j + 1) - k2
        k(i0 + 1:i0 + 8, j + 2) = k(i0 + 1:i0 + 8, j + 2) - k3
        k(i0 + 1:i0 + 8, j + 3) = k(i0 + 1:i0 + 8, j + 3) - k4
      end do
    end do
  end subroutine subtract_lower_gram

  !> m = m + w r^T d r (6 x 6): the material part of the element tangent in the strains
  !> of the element (r: the strain map into material axes, d: the material tangent).
  pure subroutine add_congruence(w, r, d, m)
    real(wp), intent(in) :: w, r(6, 6), d(6, 6)
    real(wp), intent(inout) :: m(6, 6)
    real(wp) :: dr(6, 6), rt(6, 6)
    integer :: i, j
    do j = 1, 6
      dr(:, j) = w*(d(:, 1)*r(1, j) + d(:, 2)*r(2, j) + d(:, 3)*r(3, j) + d(:, 4)*r(4, j) &
                    + d(:, 5)*r(5, j) + d(:, 6)*r(6, j))
    end do
    rt = transpose(r)
    do j = 1, 6
      do i = 1, 6
        m(:, j) = m(:, j) + rt(:, i)*dr(i, j)
      end do
    end do
  end subroutine add_congruence

  !> k = k + g s g^T (8 x 8; g: 8 x 3, s: 3 x 3): the geometric stiffness of the nodes.
  pure subroutine add_congruence_t(g, s, k)
    real(wp), intent(in) :: g(8, 3), s(3, 3)
    real(wp), intent(inout) :: k(8, 8)
    real(wp) :: gs(8, 3)
    integer :: j
    do j = 1, 3
      gs(:, j) = g(:, 1)*s(1, j) + g(:, 2)*s(2, j) + g(:, 3)*s(3, j)
    end do
    do j = 1, 8
      k(:, j) = k(:, j) + gs(:, 1)*g(j, 1) + gs(:, 2)*g(j, 2) + gs(:, 3)*g(j, 3)
    end do
  end subroutine add_congruence_t

  !> k = k + a b^T (8 x 8; a, b: 8 x 2): a geometric stiffness term of two derivative
  !> directions (the solid-shell's in-plane stresses, assumed shears and thickness stress).
  pure subroutine add_pair_product(a, b, k)
    real(wp), intent(in) :: a(8, 2), b(8, 2)
    real(wp), intent(inout) :: k(8, 8)
    integer :: j
    do j = 1, 8
      k(:, j) = k(:, j) + a(:, 1)*b(j, 1) + a(:, 2)*b(j, 2)
    end do
  end subroutine add_pair_product

end module ddpy_element_products
