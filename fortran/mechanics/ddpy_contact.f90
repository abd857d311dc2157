!> Frictional contact of a node with a rigid tool: the Alart-Curnier augmented Lagrangian
!> residual and its exact derivatives (docs/theory/contact.md).
!>
!> Unknowns of a node in contact with a tool: its displacement (in x = X + u) and the force
!> lambda (3 components) the tool exerts on it. With the closest point on the tool, the
!> outward unit normal n, the gap g = (x - S) . n and the tangential slip since the last
!> converged increment s = (I - n n) v, v = x - x_n - (u_tool - u_tool_n):
!>     p = lambda . n,  t = lambda - p n,  p_aug = p - r g
!>     inactive (p_aug <= 0):  C = lambda
!>     active:  C = r g n + C_T,  C_T = t - P_B(mu p_aug)(t - r s)
!> with P_B(rho) the projection on the disc of radius rho: stick C_T = r s, slip
!> C_T = t - mu p_aug e, e = unit(t - r s). C = 0 is the Coulomb law with the
!> Kuhn-Tucker conditions. The derivative of n along x carries the curvature of the tool:
!> dn/dx = -T a^-1 b A^-1 T^T with T = [S_,1 S_,2], a = T^T T, b_ab = n . S_,ab and
!> A = a - g b (the derivative of the closest-point parameters is A^-1 T^T).
!> contact_law gives the same law with its derivatives along g, n and v themselves, which
!> surface-to-surface contact chains through its weighted gap, normal and slip.
module ddpy_contact
  use ddpy_kinds, only: wp
  implicit none
  private
  public :: contact_residual, contact_law, normal_derivative, contact_inactive, contact_stick, &
            contact_slip, gauss_traction

  !> State of a node after the residual: no force; sticking; slipping.
  integer, parameter :: contact_inactive = 0, contact_stick = 1, contact_slip = 2

contains

  !> dn/dx at the closest point: tangents t(:, a) = S_,a, second derivatives
  !> s2(:, 1:3) = S_,11, S_,12, S_,22, gap g. Zero where the metric is singular.
  pure function normal_derivative(t, s2, n, g) result(dndx)
    real(wp), intent(in) :: t(3, 2), s2(3, 3), n(3), g
    real(wp) :: dndx(3, 3)
    real(wp) :: a(2, 2), b(2, 2), big(2, 2), ainv(2, 2), biginv(2, 2), m(2, 2), det
    a(1, 1) = dot_product(t(:, 1), t(:, 1))
    a(1, 2) = dot_product(t(:, 1), t(:, 2))
    a(2, 2) = dot_product(t(:, 2), t(:, 2))
    a(2, 1) = a(1, 2)
    b(1, 1) = dot_product(n, s2(:, 1))
    b(1, 2) = dot_product(n, s2(:, 2))
    b(2, 2) = dot_product(n, s2(:, 3))
    b(2, 1) = b(1, 2)
    big = a - g*b
    dndx = 0.0_wp
    det = a(1, 1)*a(2, 2) - a(1, 2)**2
    if (det <= 0.0_wp) return
    ainv = reshape([a(2, 2), -a(2, 1), -a(1, 2), a(1, 1)], [2, 2])/det
    det = big(1, 1)*big(2, 2) - big(1, 2)*big(2, 1)
    if (det == 0.0_wp) return
    biginv = reshape([big(2, 2), -big(2, 1), -big(1, 2), big(1, 1)], [2, 2])/det
    m = matmul(ainv, matmul(b, biginv))
    dndx = -matmul(t, matmul(m, transpose(t)))
  end function normal_derivative

  !> Residual C (3) of one node and its derivatives dC/dlambda and dC/dx (3 x 3).
  !> lambda: force of the tool on the node; n, g, dndx: from the projection; v: node
  !> displacement relative to the tool since the last converged increment; mu: friction
  !> coefficient; r: augmentation parameter (force per length).
  pure subroutine contact_residual(lambda, n, g, dndx, v, mu, r, c, dc_dlambda, dc_dx, state)
    real(wp), intent(in) :: lambda(3), n(3), g, dndx(3, 3), v(3), mu, r
    real(wp), intent(out) :: c(3), dc_dlambda(3, 3), dc_dx(3, 3)
    integer, intent(out) :: state
    real(wp) :: p, t(3), s(3), p_aug, trial(3), norm_trial, e(3), rho, eye(3, 3)
    real(wp) :: dp_dx(3), dt_dx(3, 3), ds_dx(3, 3), proj(3, 3), dtrial_dx(3, 3), de(3, 3)
    real(wp) :: nv, ntv(3), ntl(3)
    integer :: i
    eye = 0.0_wp
    do i = 1, 3
      eye(i, i) = 1.0_wp
    end do
    p = dot_product(lambda, n)
    p_aug = p - r*g
    if (p_aug <= 0.0_wp) then
      state = contact_inactive
      c = lambda
      dc_dlambda = eye
      dc_dx = 0.0_wp
      return
    end if
    proj = eye - outer(n, n)
    t = matmul(proj, lambda)
    s = matmul(proj, v)
    ! Derivatives of the slip s = (I - n n) v along x (v changes like x).
    nv = dot_product(n, v)
    ntv = matmul(transpose(dndx), v)
    ds_dx = proj - nv*dndx - outer(n, ntv)
    ! Normal part: r g n.
    c = r*g*n
    dc_dx = r*(outer(n, n) + g*dndx)
    dc_dlambda = 0.0_wp
    trial = t - r*s
    norm_trial = norm2(trial)
    rho = mu*p_aug
    if (norm_trial <= rho) then
      state = contact_stick
      c = c + r*s
      dc_dx = dc_dx + r*ds_dx
      return
    end if
    state = contact_slip
    e = trial/norm_trial
    c = c + t - rho*e
    ! t = (I - n n) lambda: dt/dlambda = I - n n, dt/dx = -(p dn/dx + n (dn/dx^T lambda)).
    ntl = matmul(transpose(dndx), lambda)
    dt_dx = -(p*dndx + outer(n, ntl))
    dp_dx = ntl
    dtrial_dx = dt_dx - r*ds_dx
    de = (eye - outer(e, e))/norm_trial
    ! rho = mu (lambda . n - r g): drho/dlambda = mu n, drho/dx = mu (dn^T lambda - r n).
    dc_dlambda = proj - mu*outer(e, n) - rho*matmul(de, proj)
    dc_dx = dc_dx + dt_dx - mu*outer(e, dp_dx - r*n) - rho*matmul(de, dtrial_dx)
  end subroutine contact_residual

  !> The law of contact_residual with its partial derivatives along its inputs rather than
  !> along one node's position: dC/dlambda, dC/dg (3), dC/dn (3 x 3, n taken as a free
  !> vector: the caller chains the derivative of its unit normal) and dC/dv (3 x 3). The
  !> surface-to-surface contact chains them through its weighted gap, normal and slip,
  !> which depend on every node of the faces around a node (docs/theory/contact.md).
  pure subroutine contact_law(lambda, n, g, v, mu, r, c, dc_dlambda, dc_dg, dc_dn, dc_dv, &
                              state)
    real(wp), intent(in) :: lambda(3), n(3), g, v(3), mu, r
    real(wp), intent(out) :: c(3), dc_dlambda(3, 3), dc_dg(3), dc_dn(3, 3), dc_dv(3, 3)
    integer, intent(out) :: state
    real(wp) :: p, t(3), s(3), p_aug, trial(3), norm_trial, e(3), rho, eye(3, 3), &
                proj(3, 3), ds_dn(3, 3), dt_dn(3, 3), de(3, 3)
    integer :: i
    eye = 0.0_wp
    do i = 1, 3
      eye(i, i) = 1.0_wp
    end do
    dc_dg = 0.0_wp
    dc_dn = 0.0_wp
    dc_dv = 0.0_wp
    p = dot_product(lambda, n)
    p_aug = p - r*g
    if (p_aug <= 0.0_wp) then
      state = contact_inactive
      c = lambda
      dc_dlambda = eye
      return
    end if
    proj = eye - outer(n, n)
    t = matmul(proj, lambda)
    s = matmul(proj, v)
    ! s = v - (v . n) n: ds/dn = -((v . n) I + n v^T), ds/dv = I - n n.
    ds_dn = -(dot_product(n, v)*eye + outer(n, v))
    c = r*g*n
    dc_dg = r*n
    dc_dn = r*g*eye
    dc_dlambda = 0.0_wp
    trial = t - r*s
    norm_trial = norm2(trial)
    rho = mu*p_aug
    if (norm_trial <= rho) then
      state = contact_stick
      c = c + r*s
      dc_dn = dc_dn + r*ds_dn
      dc_dv = r*proj
      return
    end if
    state = contact_slip
    e = trial/norm_trial
    c = c + t - rho*e
    ! t = lambda - p n: dt/dn = -(p I + n lambda^T); rho = mu (lambda . n - r g).
    dt_dn = -(p*eye + outer(n, lambda))
    de = (eye - outer(e, e))/norm_trial
    dc_dlambda = proj - mu*outer(e, n) - rho*matmul(de, proj)
    dc_dg = dc_dg + mu*r*e
    dc_dn = dc_dn + dt_dn - mu*outer(e, lambda) - rho*matmul(de, dt_dn - r*ds_dn)
    dc_dv = r*rho*matmul(de, proj)
  end subroutine contact_law

  !> Penalty law of one Gauss point of a blank face (docs/theory/contact.md, Gauss-point
  !> contact): the traction of the tool on the face per undeformed area, p n + t, with
  !> p = max(0, p_n - eps_n g) (p_n the point's pressure multiplier: 0 for the plain
  !> penalty, the augmented Lagrangian's pressure of the last augmentation otherwise, so
  !> that the point sinks only by the change of its pressure over eps_n) and Coulomb friction by a penalty stick and return mapping: the
  !> trial t_tr = (I - n n)(t_n - eps_t v) from the tangential traction t_n of the last
  !> converged increment and the slip v of the point relative to the tool since then;
  !> stick t = t_tr where |t_tr| <= mu p, else slip t = mu p t_tr / |t_tr|. Returns the
  !> traction, its tangential part (the history to keep), the pressure p, its exact
  !> derivative along the point's position (3 x 3, with the tool's curvature dndx) and the
  !> state.
  pure subroutine gauss_traction(traction_n, pressure_n, n, g, dndx, v, mu, eps_n, eps_t, &
                                 traction, tangential, pressure, dtr_dx, state)
    real(wp), intent(in) :: traction_n(3), pressure_n, n(3), g, dndx(3, 3), v(3), mu, eps_n, &
                            eps_t
    real(wp), intent(out) :: traction(3), tangential(3), pressure, dtr_dx(3, 3)
    integer, intent(out) :: state
    real(wp) :: p, eye(3, 3), proj(3, 3), w(3), trial(3), dp_dx(3), dtrial(3, 3), &
                norm_trial, rho, e(3)
    integer :: i
    traction = 0.0_wp
    tangential = 0.0_wp
    dtr_dx = 0.0_wp
    state = contact_inactive
    pressure = 0.0_wp
    p = pressure_n - eps_n*g
    if (.not. p > 0.0_wp) return
    pressure = p
    eye = 0.0_wp
    do i = 1, 3
      eye(i, i) = 1.0_wp
    end do
    proj = eye - outer(n, n)
    w = traction_n - eps_t*v
    trial = matmul(proj, w)
    dp_dx = -eps_n*n
    ! d(p n)/dx = n dp/dx + p dn/dx.
    dtr_dx = outer(n, dp_dx) + p*dndx
    ! d((I - n n) w)/dx = -((n . w) I + n w^T) dn/dx - eps_t (I - n n).
    dtrial = -matmul(dot_product(n, w)*eye + outer(n, w), dndx) - eps_t*proj
    norm_trial = norm2(trial)
    rho = mu*p
    if (norm_trial <= rho) then
      state = contact_stick
      tangential = trial
      dtr_dx = dtr_dx + dtrial
    else
      state = contact_slip
      e = trial/norm_trial
      tangential = rho*e
      dtr_dx = dtr_dx + mu*outer(e, dp_dx) + &
               rho*matmul((eye - outer(e, e))/norm_trial, dtrial)
    end if
    traction = p*n + tangential
  end subroutine gauss_traction

  pure function outer(a, b) result(m)
    real(wp), intent(in) :: a(3), b(3)
    real(wp) :: m(3, 3)
    integer :: j
    do j = 1, 3
      m(:, j) = a*b(j)
    end do
  end function outer

end module ddpy_contact
