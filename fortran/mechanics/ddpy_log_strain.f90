!> The logarithmic (Hencky) strain E = ln(U) = (1/2) ln(C) of a deformation and its first and
!> second derivatives with respect to the Green-Lagrange strain, for the updated Lagrangian
!> hexahedron (../docs/theory/solid.md).
!>
!> Everything is computed in the eigenbasis of C = I + 2 E_GL by the Daleckii-Krein formulas:
!> with f(lambda) = ln(lambda)/2, the first derivative of f(C) in direction H has the
!> eigenbasis components f[l_i, l_j] H'_ij and the second, in directions H and K,
!> sum_k f[l_i, l_k, l_j] (H'_ik K'_kj + K'_ik H'_kj), where f[.,.] and f[.,.,.] are divided
!> differences. They are evaluated in forms that stay accurate for equal and nearly equal
!> eigenvalues (the undeformed state has three), so no perturbation is needed.
!> Voigt order 11, 22, 33, 12, 23, 31; strains with engineering shears, stresses without.
module ddpy_log_strain
  use ddpy_kinds, only: wp
  implicit none
  private
  public :: hencky_type, hencky_evaluate, hencky_first, hencky_second, hencky_stretch, &
            symmetric_eigen, tensor_from_strain, strain_from_tensor, tensor_from_stress, &
            stress_from_tensor

  !> One evaluation: eigenvalues mu of 2 E_GL (C = I + 2 E_GL has 1 + mu), eigenvectors
  !> (columns), the divided differences of f, the Hencky strain (Voigt), the six unit
  !> Green-Lagrange directions, as dC = 2 dE_GL, in the eigenbasis, and the Voigt vectors
  !> (engineering shears) dyads(:, q) of the symmetric dyads of eigenvectors
  !> (v_i v_j^T + v_j v_i^T)/2 over the pairs q = (1, 1), (2, 2), (3, 3),
  !> (1, 2), (2, 3), (3, 1): direction(c, i, j) = d_c dyads(c, q(i, j)) with d = (2, 2, 2,
  !> 1, 1, 1), so that the first derivative is a sum of six symmetric rank-one terms.
  !> No default initialization: hencky_evaluate sets every component, and a default would
  !> make every intent(out) dummy and local of this type be cleared at each call (the element
  !> evaluates it at every Gauss point).
  type :: hencky_type
    real(wp) :: mu(3)
    real(wp) :: vectors(3, 3)
    real(wp) :: first(3, 3)
    real(wp) :: second(3, 3, 3)
    real(wp) :: strain(6)
    real(wp) :: direction(6, 3, 3)
    real(wp) :: dyads(6, 6)
  end type hencky_type

  !> Relative spread of three eigenvalues below which the second divided difference is taken
  !> from its Taylor series (error ~ spread^4) instead of the difference quotient (rounding
  !> ~ epsilon / spread): both near 1e-13 at 1e-3.
  real(wp), parameter :: taylor_spread = 1.0e-3_wp

contains

  !> ln(1 + x), accurate for small x (Kahan's correction of the rounded 1 + x).
  pure elemental function log_one_plus(x) result(y)
    real(wp), intent(in) :: x
    real(wp) :: y, w
    w = 1.0_wp + x
    if (w == 1.0_wp) then
      y = x
    else
      y = log(w)*x/(w - 1.0_wp)
    end if
  end function log_one_plus

  !> Symmetric 3 x 3 tensor from Voigt strain components (engineering shears halved).
  pure function tensor_from_strain(e) result(t)
    real(wp), intent(in) :: e(6)
    real(wp) :: t(3, 3)
    t = tensor_from_stress([e(1), e(2), e(3), 0.5_wp*e(4), 0.5_wp*e(5), 0.5_wp*e(6)])
  end function tensor_from_strain

  pure function strain_from_tensor(t) result(e)
    real(wp), intent(in) :: t(3, 3)
    real(wp) :: e(6)
    e = [t(1, 1), t(2, 2), t(3, 3), t(1, 2) + t(2, 1), t(2, 3) + t(3, 2), t(3, 1) + t(1, 3)]
  end function strain_from_tensor

  pure function tensor_from_stress(s) result(t)
    real(wp), intent(in) :: s(6)
    real(wp) :: t(3, 3)
    t(1, 1) = s(1)
    t(2, 2) = s(2)
    t(3, 3) = s(3)
    t(1, 2) = s(4)
    t(2, 1) = s(4)
    t(2, 3) = s(5)
    t(3, 2) = s(5)
    t(3, 1) = s(6)
    t(1, 3) = s(6)
  end function tensor_from_stress

  pure function stress_from_tensor(t) result(s)
    real(wp), intent(in) :: t(3, 3)
    real(wp) :: s(6)
    s = [t(1, 1), t(2, 2), t(3, 3), 0.5_wp*(t(1, 2) + t(2, 1)), 0.5_wp*(t(2, 3) + t(3, 2)), &
         0.5_wp*(t(3, 1) + t(1, 3))]
  end function stress_from_tensor

  !> Eigenvalues and orthonormal eigenvectors (columns) of a symmetric 3 x 3 matrix, accurate
  !> relative to the largest entry. Closed form (the trigonometric solution of the
  !> characteristic cubic, eigenvectors from cross products of the rows of A - lambda I) when
  !> the eigenvalues are apart by more than 1e-4 of the largest entry, where its eigenvectors
  !> are good to about epsilon / 1e-4; cyclic Jacobi rotations otherwise (also for repeated
  !> eigenvalues). The closed form is several times faster: no chain of square roots and
  !> divisions.
  pure subroutine symmetric_eigen(a, values, vectors)
    real(wp), intent(in) :: a(3, 3)
    real(wp), intent(out) :: values(3), vectors(3, 3)
    real(wp) :: b(3, 3), scale, q, p1, p2, p, r, phi, l(3), v(3), w(3), best(3), size, size2
    integer :: i, j
    b = 0.5_wp*(a + transpose(a))
    scale = maxval(abs(b))
    if (scale == 0.0_wp) then
      values = 0.0_wp
      vectors = 0.0_wp
      do i = 1, 3
        vectors(i, i) = 1.0_wp
      end do
      return
    end if
    b = b/scale
    q = (b(1, 1) + b(2, 2) + b(3, 3))/3.0_wp
    p1 = b(1, 2)**2 + b(1, 3)**2 + b(2, 3)**2
    p2 = (b(1, 1) - q)**2 + (b(2, 2) - q)**2 + (b(3, 3) - q)**2 + 2.0_wp*p1
    p = sqrt(p2/6.0_wp)
    if (p > 0.0_wp) then
      do i = 1, 3
        b(i, i) = b(i, i) - q
      end do
      r = 0.5_wp*(b(1, 1)*(b(2, 2)*b(3, 3) - b(2, 3)*b(3, 2)) &
                  - b(1, 2)*(b(2, 1)*b(3, 3) - b(2, 3)*b(3, 1)) &
                  + b(1, 3)*(b(2, 1)*b(3, 2) - b(2, 2)*b(3, 1)))/p**3
      phi = acos(max(-1.0_wp, min(1.0_wp, r)))/3.0_wp
      ! cos(phi + 2 pi/3) from cos and sin of phi: one sincos instead of two cos.
      l = [2.0_wp*p*cos(phi), 0.0_wp, -p*(cos(phi) + sqrt(3.0_wp)*sin(phi))]
      l(2) = -l(1) - l(3)
      if (min(l(1) - l(2), l(2) - l(3)) > 1.0e-4_wp) then
        ! Eigenvectors of the outer eigenvalues: the largest cross product of two rows of
        ! B - l I; the middle one completes the basis.
        do j = 1, 3, 2
          size = -1.0_wp
          do i = 1, 3
            v = b(:, mod(i, 3) + 1) - l(j)*unit_vector(mod(i, 3) + 1)
            w = b(:, mod(i + 1, 3) + 1) - l(j)*unit_vector(mod(i + 1, 3) + 1)
            v = [v(2)*w(3) - v(3)*w(2), v(3)*w(1) - v(1)*w(3), v(1)*w(2) - v(2)*w(1)]
            size2 = dot_product(v, v)
            if (size2 > size) then
              size = size2
              best = v
            end if
          end do
          vectors(:, j) = best/sqrt(size)
        end do
        vectors(:, 2) = [vectors(2, 3)*vectors(3, 1) - vectors(3, 3)*vectors(2, 1), &
                         vectors(3, 3)*vectors(1, 1) - vectors(1, 3)*vectors(3, 1), &
                         vectors(1, 3)*vectors(2, 1) - vectors(2, 3)*vectors(1, 1)]
        values = (l + q)*scale
        return
      end if
    end if
    call jacobi_eigen(a, values, vectors)
  end subroutine symmetric_eigen

  !> e_i, the i-th unit vector.
  pure function unit_vector(i) result(e)
    integer, intent(in) :: i
    real(wp) :: e(3)
    e = 0.0_wp
    e(i) = 1.0_wp
  end function unit_vector

  !> Eigenvalues and orthonormal eigenvectors (columns) of a symmetric 3 x 3 matrix by cyclic
  !> Jacobi rotations: accurate relative to the largest entry, also for repeated eigenvalues.
  pure subroutine jacobi_eigen(a, values, vectors)
    real(wp), intent(in) :: a(3, 3)
    real(wp), intent(out) :: values(3), vectors(3, 3)
    real(wp) :: m(3, 3), scale, theta, t, c, s, x, y
    integer :: sweep, p, q, r
    m = 0.5_wp*(a + transpose(a))
    vectors = 0.0_wp
    do p = 1, 3
      vectors(p, p) = 1.0_wp
    end do
    scale = maxval(abs(m))
    do sweep = 1, 30
      if (abs(m(1, 2)) + abs(m(1, 3)) + abs(m(2, 3)) <= 0.0_wp) exit
      do p = 1, 2
        do q = p + 1, 3
          if (abs(m(p, q)) <= 0.01_wp*epsilon(1.0_wp)*scale) then
            m(p, q) = 0.0_wp
            m(q, p) = 0.0_wp
            cycle
          end if
          theta = (m(q, q) - m(p, p))/(2.0_wp*m(p, q))
          if (abs(theta) > 1.0e100_wp) then
            t = 0.5_wp/theta
          else
            t = sign(1.0_wp, theta)/(abs(theta) + sqrt(theta*theta + 1.0_wp))
          end if
          c = 1.0_wp/sqrt(t*t + 1.0_wp)
          s = t*c
          do r = 1, 3
            x = m(r, p)
            y = m(r, q)
            m(r, p) = c*x - s*y
            m(r, q) = s*x + c*y
          end do
          do r = 1, 3
            x = m(p, r)
            y = m(q, r)
            m(p, r) = c*x - s*y
            m(q, r) = s*x + c*y
          end do
          m(p, q) = 0.0_wp
          m(q, p) = 0.0_wp
          do r = 1, 3
            x = vectors(r, p)
            y = vectors(r, q)
            vectors(r, p) = c*x - s*y
            vectors(r, q) = s*x + c*y
          end do
        end do
      end do
    end do
    values = [m(1, 1), m(2, 2), m(3, 3)]
  end subroutine jacobi_eigen

  !> First divided difference f[1 + a, 1 + b] of f = ln/2: atanh(x)/(x (2 + a + b)) with
  !> x = (a - b)/(2 + a + b), exact in form for all a, b (series for small x).
  pure function divided_first(a, b) result(d)
    real(wp), intent(in) :: a, b
    real(wp) :: d, x, sum_ab
    sum_ab = 2.0_wp + a + b
    x = (a - b)/sum_ab
    if (abs(x) < 1.0e-4_wp) then
      d = (1.0_wp + x*x*(1.0_wp/3.0_wp + 0.2_wp*x*x))/sum_ab
    else
      d = atanh(x)/(x*sum_ab)
    end if
  end function divided_first

  !> Second divided difference f[1 + a, 1 + b, 1 + c] of f = ln/2 (symmetric in its
  !> arguments): the quotient over the two most distant arguments, or the Taylor series
  !> f''/2 + f''''/24 h2 + f'''''/120 h3 about the mean (h_k: complete homogeneous symmetric
  !> polynomials of the deviations; h1 = 0).
  pure function divided_second(a, b, c) result(d)
    real(wp), intent(in) :: a, b, c
    real(wp) :: d, s(3), lm, dev(3), h2, h3
    integer :: i, j, k
    s = [min(a, b, c), 0.0_wp, max(a, b, c)]
    s(2) = a + b + c - s(1) - s(3)
    lm = 1.0_wp + (a + b + c)/3.0_wp
    if (s(3) - s(1) > taylor_spread*lm) then
      d = (divided_first(s(1), s(2)) - divided_first(s(2), s(3)))/(s(1) - s(3))
      return
    end if
    dev = s + 1.0_wp - lm
    h2 = 0.0_wp
    h3 = 0.0_wp
    do i = 1, 3
      do j = i, 3
        h2 = h2 + dev(i)*dev(j)
        do k = j, 3
          h3 = h3 + dev(i)*dev(j)*dev(k)
        end do
      end do
    end do
    d = -0.25_wp/lm**2 - 0.125_wp*h2/lm**4 + 0.1_wp*h3/lm**5
  end function divided_second

  !> Hencky strain of the Green-Lagrange strain e_gl (Voigt) and the data of its derivatives.
  !> The eigenvalues are sorted, so that a second divided difference over indices
  !> a <= b <= c has its most distant arguments at a and c; of the 9 first and 27 second
  !> divided differences only 6 and 10 are distinct.
  pure subroutine hencky_evaluate(e_gl, h)
    real(wp), intent(in) :: e_gl(6)
    type(hencky_type), intent(out) :: h
    real(wp) :: values(3), vectors(3, 3), lam(3), t, table(3, 3, 3), s3(3, 3)
    integer :: i, j, k, a, b, c, q, order(3)
    integer, parameter :: pairs(2, 6) = reshape([1, 1, 2, 2, 3, 3, 1, 2, 2, 3, 3, 1], [2, 6])
    s3(:, 1) = [e_gl(1), 0.5_wp*e_gl(4), 0.5_wp*e_gl(6)]
    s3(:, 2) = [0.5_wp*e_gl(4), e_gl(2), 0.5_wp*e_gl(5)]
    s3(:, 3) = [0.5_wp*e_gl(6), 0.5_wp*e_gl(5), e_gl(3)]
    call symmetric_eigen(s3, values, vectors)
    order = [minloc(values, 1), 0, maxloc(values, 1)]
    if (order(1) == order(3)) order(3) = merge(2, 1, order(1) == 1)
    order(2) = 6 - order(1) - order(3)
    h%mu = 2.0_wp*values(order)
    h%vectors = vectors(:, order)
    h%strain = 0.0_wp
    lam = 1.0_wp + h%mu
    do i = 1, 3
      h%first(i, i) = 0.5_wp/lam(i)
      do j = i + 1, 3
        h%first(i, j) = divided_first(h%mu(i), h%mu(j))
        h%first(j, i) = h%first(i, j)
      end do
    end do
    do a = 1, 3
      do b = a, 3
        do c = b, 3
          if (a == c) then
            table(a, b, c) = -0.25_wp/lam(a)**2
          else if (h%mu(c) - h%mu(a) > taylor_spread*(1.0_wp + (h%mu(a) + h%mu(b) &
                                                                 + h%mu(c))/3.0_wp)) then
            table(a, b, c) = (h%first(a, b) - h%first(b, c))/(h%mu(a) - h%mu(c))
          else
            table(a, b, c) = divided_second(h%mu(a), h%mu(b), h%mu(c))
          end if
        end do
      end do
    end do
    do j = 1, 3
      do k = 1, 3
        do i = 1, 3
          a = min(i, j, k)
          c = max(i, j, k)
          h%second(i, k, j) = table(a, i + j + k - a - c, c)
        end do
      end do
    end do
    ! Dyads of the eigenvector pairs; the Hencky strain sum_k f(l_k) v_k v_k^T is a sum of
    ! the first three, and the directions V^T (2 e_c) V of the unit Green-Lagrange strains
    ! (engineering shears) are the dyads read by rows.
    do q = 1, 6
      i = pairs(1, q)
      j = pairs(2, q)
      do c = 1, 6
        a = pairs(1, c)
        b = pairs(2, c)
        if (c <= 3) then
          h%dyads(c, q) = h%vectors(a, i)*h%vectors(a, j)
        else
          h%dyads(c, q) = h%vectors(a, i)*h%vectors(b, j) + h%vectors(b, i)*h%vectors(a, j)
        end if
      end do
    end do
    do k = 1, 3
      t = 0.5_wp*log_one_plus(h%mu(k))
      h%strain = h%strain + t*h%dyads(:, k)
    end do
    do c = 1, 6
      do q = 1, 6
        i = pairs(1, q)
        j = pairs(2, q)
        h%direction(c, i, j) = merge(2.0_wp, 1.0_wp, c <= 3)*h%dyads(c, q)
        h%direction(c, j, i) = h%direction(c, i, j)
      end do
    end do
  end subroutine hencky_evaluate

  !> p(:, c) = d E_Hencky / d E_GL(c) (Voigt, engineering shears on both sides).
  !> By Daleckii-Krein, p(r, c) = sum_ij first(i, j) y_ij(r) d_c y_ij(c) with y_ij the dyads:
  !> six symmetric rank-one terms (the pairs i /= j twice), then column c scaled by d_c.
  !> A subroutine rather than a function: an array function result is passed with a
  !> descriptor, and the copies through it do not vectorize.
  pure subroutine hencky_first(h, p)
    type(hencky_type), intent(in) :: h
    real(wp), intent(out) :: p(6, 6)
    real(wp) :: phi(6), yp(6, 6), acc(6, 6)
    integer :: q, r, c
    integer, parameter :: pairs(2, 6) = reshape([1, 1, 2, 2, 3, 3, 1, 2, 2, 3, 3, 1], [2, 6])
    do q = 1, 6
      phi(q) = merge(1.0_wp, 2.0_wp, q <= 3)*h%first(pairs(1, q), pairs(2, q))
      yp(:, q) = phi(q)*h%dyads(:, q)
    end do
    do c = 1, 6
      do r = c, 6
        acc(r, c) = yp(r, 1)*h%dyads(c, 1) + yp(r, 2)*h%dyads(c, 2) + yp(r, 3)*h%dyads(c, 3) &
                  + yp(r, 4)*h%dyads(c, 4) + yp(r, 5)*h%dyads(c, 5) + yp(r, 6)*h%dyads(c, 6)
      end do
    end do
    do c = 1, 6
      do r = 1, c - 1
        acc(r, c) = acc(c, r)
      end do
    end do
    p(:, 1:3) = 2.0_wp*acc(:, 1:3)
    p(:, 4:6) = acc(:, 4:6)
  end subroutine hencky_first

  !> l(c, d) = a : d2 E_Hencky / (d E_GL(c) d E_GL(d)) for a stress-like a (Voigt).
  !> A subroutine, as hencky_first.
  pure subroutine hencky_second(h, a, l)
    type(hencky_type), intent(in) :: h
    real(wp), intent(in) :: a(6)
    real(wp), intent(out) :: l(6, 6)
    ! Summed in a local array: into the result, which the compiler must assume may alias
    ! h, the loops do not vectorize.
    real(wp) :: ae(3, 3), s3(3, 3), wk(3, 3), y(3, 6), acc(6, 6)
    integer :: i, j, k, d
    ! a in the eigenbasis, V^T a V.
    s3(:, 1) = [a(1), a(4), a(6)]
    s3(:, 2) = [a(4), a(2), a(5)]
    s3(:, 3) = [a(6), a(5), a(3)]
    do j = 1, 3
      do i = 1, 3
        wk(i, j) = s3(i, 1)*h%vectors(1, j) + s3(i, 2)*h%vectors(2, j) &
                   + s3(i, 3)*h%vectors(3, j)
      end do
    end do
    do j = 1, 3
      do i = 1, 3
        ae(i, j) = h%vectors(1, i)*wk(1, j) + h%vectors(2, i)*wk(2, j) &
                   + h%vectors(3, i)*wk(3, j)
      end do
    end do
    ! l(c, d) = 2 sum_ikj ae(i, j) f[i, k, j] H_c(i, k) H_d(k, j) (the two orderings of the
    ! Daleckii-Krein sum are equal by the symmetries of a, H and f[., ., .]); for each k a
    ! form x_c^T W_k x_d with x_c = H_c(:, k) = direction(c, :, k) and
    ! W_k(i, j) = ae(i, j) f[i, k, j], summed by whole columns of l (vectorizes).
    acc = 0.0_wp
    do k = 1, 3
      do j = 1, 3
        do i = 1, 3
          wk(i, j) = ae(i, j)*h%second(i, k, j)
        end do
      end do
      do d = 1, 6
        y(:, d) = wk(:, 1)*h%direction(d, 1, k) + wk(:, 2)*h%direction(d, 2, k) &
                  + wk(:, 3)*h%direction(d, 3, k)
      end do
      do d = 1, 6
        acc(:, d) = acc(:, d) + h%direction(:, 1, k)*y(1, d) + h%direction(:, 2, k)*y(2, d) &
                  + h%direction(:, 3, k)*y(3, d)
      end do
    end do
    l = 2.0_wp*acc
  end subroutine hencky_second

  !> Right stretch U = C^(1/2) and its inverse.
  pure subroutine hencky_stretch(h, u, u_inverse)
    type(hencky_type), intent(in) :: h
    real(wp), intent(out) :: u(3, 3), u_inverse(3, 3)
    real(wp) :: root(3)
    integer :: i, j, k
    root = sqrt(1.0_wp + h%mu)
    do j = 1, 3
      do i = 1, 3
        u(i, j) = 0.0_wp
        u_inverse(i, j) = 0.0_wp
        do k = 1, 3
          u(i, j) = u(i, j) + root(k)*h%vectors(i, k)*h%vectors(j, k)
          u_inverse(i, j) = u_inverse(i, j) + h%vectors(i, k)*h%vectors(j, k)/root(k)
        end do
      end do
    end do
  end subroutine hencky_stretch

end module ddpy_log_strain
