!> Guaranteed bounds of tool patches: boxes that contain every point of a patch.
!>
!> Every patch of a tool is a polynomial, so it can be written in a Bernstein basis, and the
!> convex hull property holds: the patch lies in the convex hull of its Bernstein control
!> points. A Bezier patch of degree (n, m) has (n + 1)(m + 1) of them (converted back from
!> the centred power basis the core stores); a Nagata quadrilateral, of degree 2 in each
!> parameter, the 3 x 3 net of the biquadratic Bernstein basis; a Nagata triangle, of total
!> degree 2 on the triangle 0 <= t <= s <= 1, the 6 control points of the quadratic
!> triangular Bernstein basis (facets are Nagata patches with zero edge coefficients). The
!> hull is contained in any box that contains the control points, in any frame: here the
!> axis-aligned box, and a box in the patch's own frame (its normal and a tangent at its
!> centre), which is thin where the axis-aligned one of a tilted patch is not. Both are
!> padded by 1e-12 of the size of the coordinates against rounding, so that every point the
!> core computes on the patch lies in them (docs/theory/contact.md, "Closest points").
module ddpy_patch_bounds
  use ddpy_kinds, only: wp
  use ddpy_bezier, only: max_bezier_degree, binomial
  use ddpy_nagata, only: nagata_coefficient_count
  use ddpy_surface, only: patch_evaluate, unit_normal, surface_bezier
  implicit none
  private
  public :: patch_control_points, patch_bounds, max_control_points

  integer, parameter :: nb = max_bezier_degree
  !> Most control points of one patch: a Bezier patch of degree (6, 6).
  integer, parameter :: max_control_points = (nb + 1)**2
  !> Padding of the boxes, relative to the largest coordinate of the patch.
  real(wp), parameter :: pad_relative = 1.0e-12_wp

contains

  !> Bernstein control points cp(:, 1:ncp) of one patch, whose convex hull contains it.
  !> coef holds the patch's stride reals; degrees is read for Bezier patches only, and so
  !> is conversion (from bernstein_conversions).
  pure subroutine patch_control_points(kind, stride, coef, degrees, triangle, conversion, &
                                       cp, ncp)
    integer, intent(in) :: kind, stride, degrees(2)
    real(wp), intent(in) :: coef(stride), conversion(0:nb, 0:nb, nb)
    logical, intent(in) :: triangle
    real(wp), intent(out) :: cp(3, max_control_points)
    integer, intent(out) :: ncp
    if (kind == surface_bezier) then
      call bezier_control_points(degrees(1), degrees(2), coef, conversion, cp, ncp)
    else if (triangle) then
      call nagata_triangle_control_points(coef, cp, ncp)
    else
      call nagata_quad_control_points(coef, cp, ncp)
    end if
  end subroutine patch_control_points

  !> Bounds of npatch patches: the axis-aligned box lower(:, p) .. upper(:, p), and the box
  !> frame_lower(:, p) .. frame_upper(:, p) in the patch frame, whose orthonormal axes are
  !> frame(:, 1:3, p) (two tangents and the normal at the patch centre): a point y of the
  !> patch has frame_lower <= matmul(transpose(frame(:, :, p)), y) <= frame_upper.
  pure subroutine patch_bounds(kind, npatch, stride, coef, degrees, triangle, lower, upper, &
                               frame, frame_lower, frame_upper)
    integer, intent(in) :: kind, npatch, stride, degrees(2, npatch), triangle(npatch)
    real(wp), intent(in) :: coef(stride, npatch)
    real(wp), intent(out) :: lower(3, npatch), upper(3, npatch), frame(3, 3, npatch), &
                             frame_lower(3, npatch), frame_upper(3, npatch)
    real(wp) :: cp(3, max_control_points), q(3, max_control_points), pad, &
                conversion(0:nb, 0:nb, nb)
    integer :: p, ncp
    call bernstein_conversions(conversion)
    do p = 1, npatch
      call patch_control_points(kind, stride, coef(:, p), degrees(:, p), triangle(p) /= 0, &
                                conversion, cp, ncp)
      pad = pad_relative*maxval(abs(cp(:, 1:ncp)))
      lower(:, p) = minval(cp(:, 1:ncp), dim=2) - pad
      upper(:, p) = maxval(cp(:, 1:ncp), dim=2) + pad
      frame(:, :, p) = patch_frame(kind, stride, coef(:, p), degrees(:, p), triangle(p) /= 0)
      q(:, 1:ncp) = matmul(transpose(frame(:, :, p)), cp(:, 1:ncp))
      frame_lower(:, p) = minval(q(:, 1:ncp), dim=2) - pad
      frame_upper(:, p) = maxval(q(:, 1:ncp), dim=2) + pad
    end do
  end subroutine patch_bounds

  !> Orthonormal axes (columns) of a patch: unit S_,1 made normal to n, n x that, and the
  !> unit normal n at the centre of the domain; the global axes where the normal vanishes.
  !> Any axes give valid bounds; these make the box of a nearly flat patch thin.
  pure function patch_frame(kind, stride, coef, degrees, triangle) result(axes)
    integer, intent(in) :: kind, stride, degrees(2)
    real(wp), intent(in) :: coef(stride)
    logical, intent(in) :: triangle
    real(wp) :: axes(3, 3)
    real(wp) :: point(3), d1(3, 2), d2(3, 3), n(3), e(3), s, t
    integer :: i
    if (triangle) then
      s = 2.0_wp/3.0_wp; t = 1.0_wp/3.0_wp
    else
      s = 0.5_wp; t = 0.5_wp
    end if
    call patch_evaluate(kind, stride, coef, degrees, s, t, point, d1, d2)
    n = unit_normal(d1)
    e = d1(:, 1) - dot_product(d1(:, 1), n)*n
    axes = 0.0_wp
    if (norm2(n) == 0.0_wp .or. norm2(e) == 0.0_wp) then
      do i = 1, 3
        axes(i, i) = 1.0_wp
      end do
      return
    end if
    axes(:, 1) = e/norm2(e)
    axes(:, 3) = n
    axes(:, 2) = [n(2)*axes(3, 1) - n(3)*axes(2, 1), n(3)*axes(1, 1) - n(1)*axes(3, 1), &
                  n(1)*axes(2, 1) - n(2)*axes(1, 1)]
  end function patch_frame

  !> conversion(0:n, 0:n, n) = B of monomial_to_bernstein about the centre 1/2, for every
  !> degree n of a Bezier patch.
  pure subroutine bernstein_conversions(conversion)
    real(wp), intent(out) :: conversion(0:nb, 0:nb, nb)
    integer :: n
    conversion = 0.0_wp
    do n = 1, nb
      call monomial_to_bernstein(n, 0.5_wp, conversion(0:n, 0:n, n))
    end do
  end subroutine bernstein_conversions

  !> B(i, k), 0 <= i, k <= n: the Bernstein coefficients of the monomial w^k of degree n,
  !> w^k = sum_i B(i, k) B_i^n(u), with w = u (centre 0) or w = u - 1/2 (centre 1/2).
  !> From u^j = sum_{i >= j} C(i, j)/C(n, j) B_i^n(u) and the binomial expansion of
  !> (u - centre)^k.
  pure subroutine monomial_to_bernstein(n, centre, b)
    integer, intent(in) :: n
    real(wp), intent(in) :: centre
    real(wp), intent(out) :: b(0:n, 0:n)
    integer :: i, j, k
    b = 0.0_wp
    do k = 0, n
      do j = 0, k
        ! (u - centre)^k = sum_j C(k, j) u^j (-centre)^(k - j)
        do i = j, n
          b(i, k) = b(i, k) + binomial(k, j)*(-centre)**(k - j)*binomial(i, j)/binomial(n, j)
        end do
      end do
    end do
  end subroutine monomial_to_bernstein

  !> Control net of a Bezier patch from its centred power-basis coefficients
  !> (ddpy_bezier): P = B_n A B_m^T per coordinate, B from bernstein_conversions.
  pure subroutine bezier_control_points(nu, nv, coef, conversion, cp, ncp)
    integer, intent(in) :: nu, nv
    real(wp), intent(in) :: coef(3, 0:nb, 0:nb), conversion(0:nb, 0:nb, nb)
    real(wp), intent(out) :: cp(3, max_control_points)
    integer, intent(out) :: ncp
    real(wp) :: half(3, 0:nb, 0:nb)
    integer :: i, k, l, m
    ! half(:, i, m) = sum_k B_n(i, k) A(:, k, m), then P(:, i, l) = sum_m half(:, i, m) B_m(l, m)
    do m = 0, nv
      do i = 0, nu
        half(:, i, m) = 0.0_wp
        do k = 0, nu
          half(:, i, m) = half(:, i, m) + conversion(i, k, nu)*coef(:, k, m)
        end do
      end do
    end do
    ncp = 0
    do l = 0, nv
      do i = 0, nu
        ncp = ncp + 1
        cp(:, ncp) = 0.0_wp
        do m = 0, nv
          cp(:, ncp) = cp(:, ncp) + half(:, i, m)*conversion(l, m, nv)
        end do
      end do
    end do
  end subroutine bezier_control_points

  !> The 3 x 3 biquadratic control net of a Nagata quadrilateral. Its coefficients
  !> c00, c10, c01, c11, c20, c02, c21, c12 (ddpy_nagata) are the power coefficients a_kl
  !> of s^k t^l, k, l <= 2 (a_22 = 0); s^k = sum_i C(i, k)/C(2, k) B_i^2(s), so in each
  !> direction the control values of 1, s, s^2 are (1, 1, 1), (0, 1/2, 1), (0, 0, 1).
  pure subroutine nagata_quad_control_points(coef, cp, ncp)
    real(wp), intent(in) :: coef(3, nagata_coefficient_count)
    real(wp), intent(out) :: cp(3, max_control_points)
    integer, intent(out) :: ncp
    real(wp) :: row(3, 0:2, 0:2)
    integer :: j
    ! row(:, j, k): the control value at t-index j of the s^k part, sum_l b(j, l) a_kl.
    row(:, 0, 0) = coef(:, 1)
    row(:, 1, 0) = coef(:, 1) + 0.5_wp*coef(:, 3)
    row(:, 2, 0) = coef(:, 1) + coef(:, 3) + coef(:, 6)
    row(:, 0, 1) = coef(:, 2)
    row(:, 1, 1) = coef(:, 2) + 0.5_wp*coef(:, 4)
    row(:, 2, 1) = coef(:, 2) + coef(:, 4) + coef(:, 8)
    row(:, 0, 2) = coef(:, 5)
    row(:, 1, 2) = coef(:, 5) + 0.5_wp*coef(:, 7)
    row(:, 2, 2) = coef(:, 5) + coef(:, 7)
    ncp = 9
    do j = 0, 2
      cp(:, 3*j + 1) = row(:, j, 0)
      cp(:, 3*j + 2) = row(:, j, 0) + 0.5_wp*row(:, j, 1)
      cp(:, 3*j + 3) = row(:, j, 0) + row(:, j, 1) + row(:, j, 2)
    end do
  end subroutine nagata_quad_control_points

  !> The 6 quadratic triangular control points of a Nagata triangle on 0 <= t <= s <= 1.
  !> With the barycentric coordinates l1 = 1 - s, l2 = s - t, l3 = t (so s = l2 + l3,
  !> t = l3, 1 = l1 + l2 + l3), every monomial of degree <= 2 is written as a quadratic form
  !> in (l1, l2, l3); the control point of l_a^2 is its coefficient, that of l_a l_b half of
  !> it (the basis is l_a^2 and 2 l_a l_b).
  pure subroutine nagata_triangle_control_points(coef, cp, ncp)
    real(wp), intent(in) :: coef(3, nagata_coefficient_count)
    real(wp), intent(out) :: cp(3, max_control_points)
    integer, intent(out) :: ncp
    real(wp) :: a00(3), a10(3), a01(3), a11(3), a20(3), a02(3)
    a00 = coef(:, 1); a10 = coef(:, 2); a01 = coef(:, 3)
    a11 = coef(:, 4); a20 = coef(:, 5); a02 = coef(:, 6)
    ncp = 6
    cp(:, 1) = a00                                               ! l1^2: corner (0, 0)
    cp(:, 2) = a00 + a10 + a20                                   ! l2^2: corner (1, 0)
    cp(:, 3) = a00 + a10 + a01 + a11 + a20 + a02                 ! l3^2: corner (1, 1)
    cp(:, 4) = a00 + 0.5_wp*a10                                  ! l1 l2
    cp(:, 5) = a00 + 0.5_wp*(a10 + a01)                          ! l1 l3
    cp(:, 6) = a00 + a10 + 0.5_wp*(a01 + a11) + a20              ! l2 l3
  end subroutine nagata_triangle_control_points

end module ddpy_patch_bounds
