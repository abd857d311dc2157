!> The 8-node hexahedron at large strains and rotations (../docs/theory/solid.md).
!>
!> Kinematics in the reference configuration: F = I + grad_X u, Green-Lagrange strain
!> E = (F^T F - I)/2 with a mean-dilatation modification against volumetric locking,
!> Ebar = E + (tr E_mean - tr E) I/3, where tr E_mean is the volume average of tr E over the
!> element (2 x 2 x 2 Gauss points). Ebar = E for a homogeneous deformation (patch test) and
!> is quadratic in u, so its first and second derivatives, and with them the tangent, are
!> exact. The material works on increments of Ebar and on the second Piola-Kirchhoff stress
!> S in material axes (rolling direction rotated by an angle about z), both invariant under
!> rigid rotations: the update is objective and the orthotropy axes are convected.
!> Voigt order 11, 22, 33, 12, 23, 31 with engineering shear strains throughout.
module ddpy_hex8
  use ddpy_kinds, only: wp
  use ddpy_material, only: material_update, material_prop_count
  implicit none
  private
  public :: hex8_element, hex8_jacobians, hex8_stresses, strain_rotation

  !> Status values of hex8_element.
  integer, parameter, public :: hex8_ok = 0, hex8_inverted = 1, hex8_material_failed = 2

  !> Natural coordinates of the corners; the Gauss points are the corners / sqrt(3).
  real(wp), parameter :: corner(3, 8) = reshape([ &
    -1.0_wp, -1.0_wp, -1.0_wp, 1.0_wp, -1.0_wp, -1.0_wp, 1.0_wp, 1.0_wp, -1.0_wp, &
    -1.0_wp, 1.0_wp, -1.0_wp, -1.0_wp, -1.0_wp, 1.0_wp, 1.0_wp, -1.0_wp, 1.0_wp, &
    1.0_wp, 1.0_wp, 1.0_wp, -1.0_wp, 1.0_wp, 1.0_wp], [3, 8])
  real(wp), parameter :: gauss = 0.577350269189625764509148780502_wp

  !> Index pairs (i, j) of the Voigt components.
  integer, parameter :: voigt(2, 6) = reshape([1, 1, 2, 2, 3, 3, 1, 2, 2, 3, 3, 1], [2, 6])

contains

  !> Shape functions and their natural derivatives dn(a, j) = dN_a/dxi_j at xi.
  pure subroutine shape_functions(xi, n, dn)
    real(wp), intent(in) :: xi(3)
    real(wp), intent(out) :: n(8), dn(8, 3)
    real(wp) :: p(3)
    integer :: a
    do a = 1, 8
      p = 1.0_wp + corner(:, a)*xi
      n(a) = 0.125_wp*p(1)*p(2)*p(3)
      dn(a, 1) = 0.125_wp*corner(1, a)*p(2)*p(3)
      dn(a, 2) = 0.125_wp*corner(2, a)*p(1)*p(3)
      dn(a, 3) = 0.125_wp*corner(3, a)*p(1)*p(2)
    end do
  end subroutine shape_functions

  pure function det3(a) result(d)
    real(wp), intent(in) :: a(3, 3)
    real(wp) :: d
    d = a(1, 1)*(a(2, 2)*a(3, 3) - a(2, 3)*a(3, 2)) &
        - a(1, 2)*(a(2, 1)*a(3, 3) - a(2, 3)*a(3, 1)) &
        + a(1, 3)*(a(2, 1)*a(3, 2) - a(2, 2)*a(3, 1))
  end function det3

  !> Reference gradients g(a, J) = dN_a/dX_J and det J0 at natural point xi; g = 0 when
  !> det J0 <= 0.
  pure subroutine reference_gradients(x, xi, g, detj)
    real(wp), intent(in) :: x(3, 8), xi(3)
    real(wp), intent(out) :: g(8, 3), detj
    real(wp) :: n(8), dn(8, 3), jac(3, 3), inv(3, 3)
    call shape_functions(xi, n, dn)
    jac = matmul(x, dn)
    detj = det3(jac)
    if (detj <= 0.0_wp) then
      g = 0.0_wp
      return
    end if
    inv(1, 1) = jac(2, 2)*jac(3, 3) - jac(2, 3)*jac(3, 2)
    inv(1, 2) = jac(1, 3)*jac(3, 2) - jac(1, 2)*jac(3, 3)
    inv(1, 3) = jac(1, 2)*jac(2, 3) - jac(1, 3)*jac(2, 2)
    inv(2, 1) = jac(2, 3)*jac(3, 1) - jac(2, 1)*jac(3, 3)
    inv(2, 2) = jac(1, 1)*jac(3, 3) - jac(1, 3)*jac(3, 1)
    inv(2, 3) = jac(1, 3)*jac(2, 1) - jac(1, 1)*jac(2, 3)
    inv(3, 1) = jac(2, 1)*jac(3, 2) - jac(2, 2)*jac(3, 1)
    inv(3, 2) = jac(1, 2)*jac(3, 1) - jac(1, 1)*jac(3, 2)
    inv(3, 3) = jac(1, 1)*jac(2, 2) - jac(1, 2)*jac(2, 1)
    g = matmul(dn, inv)/detj
  end subroutine reference_gradients

  !> det J0 of the reference element at the 8 Gauss points (1:8) and the 8 corners (9:16).
  pure subroutine hex8_jacobians(x, detj)
    real(wp), intent(in) :: x(3, 8)
    real(wp), intent(out) :: detj(16)
    real(wp) :: n(8), dn(8, 3)
    integer :: p
    do p = 1, 8
      call shape_functions(gauss*corner(:, p), n, dn)
      detj(p) = det3(matmul(x, dn))
      call shape_functions(corner(:, p), n, dn)
      detj(8 + p) = det3(matmul(x, dn))
    end do
  end subroutine hex8_jacobians

  !> Voigt strain transformation t (engineering shears) from global axes to material axes
  !> rotated by angle (radians) about z: strain_material = t strain_global. The stress goes
  !> back as stress_global = t^T stress_material and the tangent as t^T D t.
  pure function strain_rotation(angle) result(t)
    real(wp), intent(in) :: angle
    real(wp) :: t(6, 6)
    real(wp) :: q(3, 3)
    integer :: r, c, i, j, k, l
    q = 0.0_wp
    q(1, 1) = cos(angle)
    q(1, 2) = sin(angle)
    q(2, 1) = -sin(angle)
    q(2, 2) = cos(angle)
    q(3, 3) = 1.0_wp
    do c = 1, 6
      k = voigt(1, c)
      l = voigt(2, c)
      do r = 1, 6
        i = voigt(1, r)
        j = voigt(2, r)
        if (c <= 3) then
          t(r, c) = q(i, k)*q(j, k)
        else
          t(r, c) = 0.5_wp*(q(i, k)*q(j, l) + q(i, l)*q(j, k))
        end if
        if (r > 3) t(r, c) = 2.0_wp*t(r, c)
      end do
    end do
  end function strain_rotation

  !> Green-Lagrange strain (Voigt, engineering shears) of a deformation gradient.
  pure function green_lagrange(f) result(e)
    real(wp), intent(in) :: f(3, 3)
    real(wp) :: e(6)
    real(wp) :: c(3, 3)
    c = matmul(transpose(f), f)
    e = [0.5_wp*(c(1, 1) - 1.0_wp), 0.5_wp*(c(2, 2) - 1.0_wp), 0.5_wp*(c(3, 3) - 1.0_wp), &
         c(1, 2), c(2, 3), c(3, 1)]
  end function green_lagrange

  !> Internal force, tangent (lower triangle and its mirror) and updated material state of
  !> one element.
  !>
  !> x: reference coordinates, u: total displacements of the 8 nodes; rot: strain_rotation
  !> of the element's material axes. State per Gauss point at the last converged increment:
  !> stress_old (S in material axes), ep_old, strain_old (Ebar, global axes). Out: the trial
  !> state at u (stress, ep, strain), f = sum W Bbar^T S, k = d f / d u (full 24 x 24,
  !> symmetric; only when want_tangent), status hex8_ok, hex8_inverted (det J0 or det F <= 0
  !> at a Gauss point) or hex8_material_failed.
  pure subroutine hex8_element(x, u, props, rot, stress_old, ep_old, strain_old, &
                               want_tangent, f, k, stress, ep, strain, status)
    real(wp), intent(in) :: x(3, 8), u(3, 8), props(material_prop_count), rot(6, 6)
    real(wp), intent(in) :: stress_old(6, 8), ep_old(8), strain_old(6, 8)
    logical, intent(in) :: want_tangent
    real(wp), intent(out) :: f(24), k(24, 24), stress(6, 8), ep(8), strain(6, 8)
    integer, intent(out) :: status
    real(wp) :: g(8, 3, 8), w(8), e(6, 8), b(6, 24, 8), btr(24, 8), tr(8)
    real(wp) :: fg(3, 3), vol, trbar, bbar_tr(24), g2(8, 8), kg(8, 8), bb(6, 24), db(6, 24), &
                bt(24, 6)
    real(wp) :: de(6), s_mat(6), d_mat(6, 6), s(6), d(6, 6), s3(3, 3), sg(3, 8), ptr, ptr_sum
    integer :: p, a, c, i, j, col, mstatus
    logical :: plastic, rotated

    ! Material axes = global axes (the common case): skip the rotations.
    rotated = .false.
    do j = 1, 6
      do i = 1, 6
        if (rot(i, j) /= merge(1.0_wp, 0.0_wp, i == j)) rotated = .true.
      end do
    end do
    f = 0.0_wp
    k = 0.0_wp
    stress = stress_old
    ep = ep_old
    strain = strain_old
    status = hex8_ok

    ! Pass 1: gradients, strains and their first derivatives at the Gauss points.
    do p = 1, 8
      call reference_gradients(x, gauss*corner(:, p), g(:, :, p), w(p))
      if (w(p) <= 0.0_wp) then
        status = hex8_inverted
        return
      end if
      fg = matmul(u, g(:, :, p))
      do i = 1, 3
        fg(i, i) = fg(i, i) + 1.0_wp
      end do
      if (det3(fg) <= 0.0_wp) then
        status = hex8_inverted
        return
      end if
      e(:, p) = green_lagrange(fg)
      tr(p) = e(1, p) + e(2, p) + e(3, p)
      do a = 1, 8
        do c = 1, 3
          col = 3*(a - 1) + c
          b(1, col, p) = fg(c, 1)*g(a, 1, p)
          b(2, col, p) = fg(c, 2)*g(a, 2, p)
          b(3, col, p) = fg(c, 3)*g(a, 3, p)
          b(4, col, p) = fg(c, 1)*g(a, 2, p) + fg(c, 2)*g(a, 1, p)
          b(5, col, p) = fg(c, 2)*g(a, 3, p) + fg(c, 3)*g(a, 2, p)
          b(6, col, p) = fg(c, 3)*g(a, 1, p) + fg(c, 1)*g(a, 3, p)
        end do
      end do
      btr(:, p) = b(1, :, p) + b(2, :, p) + b(3, :, p)
    end do

    ! Volume averages of tr E, of its gradient and of its second derivative (g2).
    vol = sum(w)
    trbar = dot_product(w, tr)/vol
    bbar_tr = matmul(btr, w)/vol
    if (want_tangent) then
      g2 = 0.0_wp
      do p = 1, 8
        g2 = g2 + w(p)*matmul(g(:, :, p), transpose(g(:, :, p)))
      end do
      g2 = g2/vol
      kg = 0.0_wp
      ptr_sum = 0.0_wp
    end if

    ! Pass 2: mean-dilatation strain, material update, force and tangent.
    do p = 1, 8
      strain(:, p) = e(:, p)
      strain(1:3, p) = strain(1:3, p) + (trbar - tr(p))/3.0_wp
      bb = b(:, :, p)
      do i = 1, 3
        bb(i, :) = bb(i, :) + (bbar_tr - btr(:, p))/3.0_wp
      end do
      de = strain(:, p) - strain_old(:, p)
      if (rotated) de = matmul(rot, de)
      call material_update(props, stress_old(:, p), ep_old(p), de, s_mat, ep(p), d_mat, &
                           plastic, mstatus)
      if (mstatus > 0) then
        status = hex8_material_failed
        return
      end if
      stress(:, p) = s_mat
      if (rotated) then
        s = matmul(transpose(rot), s_mat)
      else
        s = s_mat
      end if
      f = f + w(p)*matmul(s, bb)
      if (.not. want_tangent) cycle

      ! Material part W Bbar^T D Bbar, lower triangle, vectorized along the columns.
      if (rotated) then
        d = matmul(transpose(rot), matmul(d_mat, rot))
        db = w(p)*matmul(d, bb)
      else
        db = w(p)*matmul(d_mat, bb)
      end if
      bt = transpose(bb)
      do j = 1, 24
        do i = j, 24
          k(i, j) = k(i, j) + bt(i, 1)*db(1, j) + bt(i, 2)*db(2, j) + bt(i, 3)*db(3, j) &
                    + bt(i, 4)*db(4, j) + bt(i, 5)*db(5, j) + bt(i, 6)*db(6, j)
        end do
      end do
      ! Geometric part S : d2Ebar/du2 = S : d2E + tr S/3 (d2 trE_mean - d2 trE).
      s3 = reshape([s(1), s(4), s(6), s(4), s(2), s(5), s(6), s(5), s(3)], [3, 3])
      ptr = w(p)*(s(1) + s(2) + s(3))/3.0_wp
      sg = matmul(s3, transpose(g(:, :, p)))
      kg = kg + w(p)*matmul(g(:, :, p), sg) - ptr*matmul(g(:, :, p), transpose(g(:, :, p)))
      ptr_sum = ptr_sum + ptr
    end do
    if (.not. want_tangent) return

    kg = kg + ptr_sum*g2
    do j = 1, 8
      do i = j, 8
        do c = 1, 3
          k(3*(i - 1) + c, 3*(j - 1) + c) = k(3*(i - 1) + c, 3*(j - 1) + c) + kg(i, j)
        end do
      end do
    end do
    ! Entries (3(i-1)+c, 3(i-1)+c') with c < c' of the same node lie above the diagonal and
    ! receive nothing from kg; mirror the lower triangle to the upper.
    do j = 2, 24
      do i = 1, j - 1
        k(i, j) = k(j, i)
      end do
    end do
  end subroutine hex8_element

  !> Stresses and positions at the 8 Gauss points: second Piola-Kirchhoff stress in global
  !> axes (pk2 = rot^T stress_mat), Cauchy stress sigma = F S F^T / det F, and the current
  !> positions of the points. Status hex8_inverted when det J0 or det F <= 0.
  pure subroutine hex8_stresses(x, u, rot, stress_mat, pk2, cauchy, points, status)
    real(wp), intent(in) :: x(3, 8), u(3, 8), rot(6, 6), stress_mat(6, 8)
    real(wp), intent(out) :: pk2(6, 8), cauchy(6, 8), points(3, 8)
    integer, intent(out) :: status
    real(wp) :: g(8, 3), detj, fg(3, 3), s3(3, 3), sig(3, 3), n(8), dn(8, 3), jf
    integer :: p, i
    status = hex8_ok
    pk2 = 0.0_wp
    cauchy = 0.0_wp
    do p = 1, 8
      call shape_functions(gauss*corner(:, p), n, dn)
      points(:, p) = matmul(x + u, n)
      call reference_gradients(x, gauss*corner(:, p), g, detj)
      fg = matmul(u, g)
      do i = 1, 3
        fg(i, i) = fg(i, i) + 1.0_wp
      end do
      jf = det3(fg)
      if (detj <= 0.0_wp .or. jf <= 0.0_wp) then
        status = hex8_inverted
        cycle
      end if
      pk2(:, p) = matmul(transpose(rot), stress_mat(:, p))
      s3 = reshape([pk2(1, p), pk2(4, p), pk2(6, p), pk2(4, p), pk2(2, p), pk2(5, p), &
                    pk2(6, p), pk2(5, p), pk2(3, p)], [3, 3])
      sig = matmul(fg, matmul(s3, transpose(fg)))/jf
      cauchy(:, p) = [sig(1, 1), sig(2, 2), sig(3, 3), sig(1, 2), sig(2, 3), sig(3, 1)]
    end do
  end subroutine hex8_stresses

end module ddpy_hex8
